"""Seeded mutations of valid documents: hostile values where the structure expects others.

Every mutation starts from a valid document (a message, a record, a
snapshot, a vector file, a trace line...) and changes one to three places:
a value replaced by a hostile one (huge and negative integers, NaN and the
infinities, NUL and lone surrogates, very long strings, the wrong JSON type,
deep nesting), a key removed or added, a list element dropped or doubled.
Texts are also cut, spliced and given bytes that are not UTF-8.
"""

from __future__ import annotations

import copy
import json
import random
from collections.abc import Callable
from typing import Any

_DEEP: Any = []
for _ in range(300):
    _DEEP = [_DEEP]

#: Values that break assumptions: every JSON type, the edges of every wire range, and beyond.
HOSTILE: tuple[Any, ...] = (
    None,
    True,
    False,
    0,
    -1,
    1,
    255,
    256,
    2**31,
    2**32,
    2**32 - 1,
    2**63,
    2**64 - 1,
    2**64,
    -(2**63) - 1,
    10**400,
    -(10**400),
    0.5,
    -0.0,
    1e-320,
    1e300,
    -1e300,
    float("nan"),
    float("inf"),
    float("-inf"),
    "",
    " ",
    "x",
    "\x00",
    "\ud800",
    "\udfff",
    "é" * 40,
    "🤖",
    "a" * 70_000,
    "{}",
    "[]",
    "0",
    "1e999",
    '"quoted"',
    "dynamic_event",
    "*",
    [],
    [1, "a", None],
    {},
    {"type": "tick"},
    {"": None},
    _DEEP,
)


def hostile(rng: random.Random) -> Any:
    """One hostile value (a fresh copy: later mutations never change the table)."""
    value = rng.choice(HOSTILE)
    return copy.deepcopy(value) if isinstance(value, (list, dict)) else value


def _near(value: Any, rng: random.Random) -> Any:
    """A value close to ``value``: the same type, at or past an edge."""
    if isinstance(value, bool):
        choices: list[Callable[[], Any]] = [lambda: not value, lambda: int(value)]
    elif isinstance(value, int):
        choices = [
            lambda: value + 1,
            lambda: value - 1,
            lambda: -value,
            lambda: value * 2**32,
            lambda: value + 2**64,
            lambda: str(value),
            lambda: float(value),
        ]
    elif isinstance(value, float):
        choices = [
            lambda: value * 1e308,
            lambda: -value,
            lambda: value + 2**53,
            lambda: int(value),
            lambda: str(value),
        ]
    elif isinstance(value, str):
        choices = [
            lambda: value + "\x00",
            lambda: (value * 1000)[:100_000],
            lambda: value[: len(value) // 2],
            value.upper,
            lambda: f'"{value}"',
        ]
    else:
        return hostile(rng)
    try:
        return rng.choice(choices)()
    except (OverflowError, ValueError):  # int(inf), float(10**400): a hostile value instead
        return hostile(rng)


def mutate_json(value: Any, rng: random.Random, mutations: int | None = None) -> Any:
    """``value`` (a JSON document, not changed) with one to three places made hostile."""
    result = json.loads(json.dumps(value))
    for _ in range(mutations if mutations is not None else rng.randint(1, 3)):
        result = _mutate_once(result, rng)
    return result


def _mutate_once(value: Any, rng: random.Random) -> Any:
    if isinstance(value, dict) and value and rng.random() < 0.85:
        key = rng.choice(list(value))
        roll = rng.random()
        if roll < 0.6:
            value[key] = _mutate_once(value[key], rng)
        elif roll < 0.75:
            del value[key]
        elif roll < 0.9:
            value[rng.choice(["extra", "type", "__proto__", key + "_", ""])] = hostile(rng)
        else:
            value[key] = _near(value[key], rng)
        return value
    if isinstance(value, list) and value and rng.random() < 0.85:
        index = rng.randrange(len(value))
        roll = rng.random()
        if roll < 0.6:
            value[index] = _mutate_once(value[index], rng)
        elif roll < 0.75:
            del value[index]
        elif roll < 0.9:
            value.insert(index, value[index] if rng.random() < 0.5 else hostile(rng))
        else:
            value.append(hostile(rng))
        return value
    return _near(value, rng) if rng.random() < 0.4 else hostile(rng)


def dumps(value: Any) -> str:
    """JSON text of a mutated document (NaN and the infinities as Python writes them)."""
    return json.dumps(value, ensure_ascii=False, allow_nan=True)


def mutate_text(text: str, rng: random.Random) -> str | bytes:
    """``text`` cut, spliced, or given bytes that are not UTF-8."""
    roll = rng.random()
    if not text:
        return rng.choice(["", "\n", "{", "\x00"])
    cut = rng.randrange(len(text) + 1)
    if roll < 0.2:
        return text[:cut]
    if roll < 0.35:
        return (
            text[:cut] + rng.choice(['"', "{", "}", "[", "]", ",", ":", "\\", "\x00", "9" * 400]) + text[cut:]
        )
    if roll < 0.5:
        other = rng.randrange(len(text) + 1)
        return text[: min(cut, other)] + text[max(cut, other) :]
    if roll < 0.6:
        return text.encode("utf-8", "surrogatepass")[:cut] + bytes([rng.choice([0x80, 0xC3, 0xFF, 0xED])])
    if roll < 0.7:
        return text + text[:cut]
    return text.replace(
        rng.choice(["1", "0", '"', ":", ","]), rng.choice(["9" * 30, "-", "", "1e400", "NaN"]), 1
    )
