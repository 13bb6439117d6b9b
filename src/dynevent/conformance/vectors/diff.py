"""How an implementation's answer is held to a vector's expectation, and where the two differ.

:func:`matches` is the one comparison (exact, but ``"*"`` in an expectation
matches any string); :func:`differences` says where a mismatch lies, field by
field, as paths a reader can follow into the JSON (``outputs[2].rejection.text``).
Output lists are compared along a longest common subsequence (:func:`align`),
so one output too many or too few is reported alone, not as a shift of every
output after it.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any, Literal

import attrs

from dynevent.wire import _json

__all__ = [
    "MAX_DIFFERENCES",
    "MAX_KEPT_VALUE",
    "VALUE_LINES",
    "WILDCARD",
    "Difference",
    "align",
    "differences",
    "kept",
    "labelled",
    "matches",
]

#: In an expected output, matches any string.
WILDCARD = "*"

#: How a value differs: present on both sides but unequal, expected but absent, present but not expected.
Kind = Literal["differs", "missing", "unexpected"]


def matches(expected: Any, got: Any) -> bool:
    """Does ``got`` fit ``expected``?  Exact, but ``"*"`` matches any string; numbers by value."""
    if expected == WILDCARD and isinstance(got, str):
        return True
    if isinstance(expected, dict):
        return (
            isinstance(got, dict)
            and expected.keys() == got.keys()
            and all(matches(value, got[key]) for key, value in expected.items())
        )
    if isinstance(expected, list):
        return isinstance(got, list) and len(expected) == len(got) and all(map(matches, expected, got))
    if isinstance(expected, bool) or isinstance(got, bool):
        return expected is got
    return bool(expected == got)


@attrs.frozen
class Difference:
    """One place where the implementation's answer and the expectation part.

    ``path`` leads from the compared root (``outputs`` or ``view``) to the value:
    ``outputs[2].rejection.text``.  A list index is the position in the
    implementation's list, except for a ``missing`` item, where it is the
    position in the expected one.  ``expected`` is None for an ``unexpected``
    value and ``got`` None for a ``missing`` one.
    """

    path: str
    kind: Kind
    expected: Any = None
    got: Any = None

    def describe(self, width: int = 100) -> list[str]:
        """The difference as text lines of at most ``width`` columns: a value too long for the line
        follows on lines of its own, wrapped, up to :data:`VALUE_LINES` of them (then cut, ``...``)."""
        if self.kind == "missing":
            return labelled(f"{self.path}: missing, expected", self.expected, width)
        if self.kind == "unexpected":
            return labelled(f"{self.path}: not expected, got", self.got, width)
        one_line = f"{self.path}: expected {_json.dumps(self.expected)}, got {_json.dumps(self.got)}"
        if len(one_line) <= width:
            return [one_line]
        return [
            f"{self.path}:"[:width],
            *labelled("  expected", self.expected, width),
            *labelled("  got", self.got, width),
        ]

    def record(self) -> dict[str, Any]:
        """The difference as a JSON object (``dynevent vectors --json``)."""
        return {"path": self.path, "kind": self.kind, "expected": self.expected, "got": self.got}


#: The most lines one value takes in a text account (the JSON records keep every value whole).
VALUE_LINES = 6
#: The most differences a failure lists (its text account and its JSON record alike); the rest are
#: counted: an answer of 60,000 outputs where one was expected is one failure, not 60,000 accounts.
MAX_DIFFERENCES = 16
#: The most JSON text of one value a failure keeps (the answer, a difference's two sides): a larger
#: value is named by its size, so that a run of many failures holds no more than a few of these.
MAX_KEPT_VALUE = 64 * 1024


def kept(value: Any) -> Any:
    """``value`` as a failure keeps it: itself, or, when its JSON text is longer than
    :data:`MAX_KEPT_VALUE` characters, a string that says so (written only up to that length)."""
    written = 0
    for piece in _ENCODER.iterencode(value):
        written += len(piece)
        if written > MAX_KEPT_VALUE:
            return f"<a value of more than {MAX_KEPT_VALUE:,} characters of JSON, not kept>"
    return value


#: Writes as :func:`dynevent.wire._json.dumps` does, a piece at a time.
_ENCODER = json.JSONEncoder(separators=(",", ":"), ensure_ascii=False)


def labelled(label: str, value: Any, width: int) -> list[str]:
    """``label: value`` (the value as JSON) on one line if it fits within ``width`` columns, else
    ``label:`` and the value wrapped beneath it, up to :data:`VALUE_LINES` lines."""
    text = _json.dumps(value)
    if len(label) + 2 + len(text) <= width:
        return [f"{label}: {text}"]
    indent = " " * (len(label) - len(label.lstrip()) + 4)
    room = max(width - len(indent), 20)
    chunks = [text[start : start + room] for start in range(0, len(text), room)]
    if len(chunks) > VALUE_LINES:
        chunks = [*chunks[: VALUE_LINES - 1], chunks[VALUE_LINES - 1][: room - 3] + "..."]
    return [f"{label}:", *(indent + chunk for chunk in chunks)]


def differences(expected: Any, got: Any, path: str) -> list[Difference]:
    """Every place where ``got`` does not fit ``expected`` (empty when it :func:`matches`)."""
    if matches(expected, got):
        return []
    if isinstance(expected, dict) and isinstance(got, dict):
        found: list[Difference] = []
        for key, value in expected.items():
            where = f"{path}.{key}"
            if key in got:
                found.extend(differences(value, got[key], where))
            else:
                found.append(Difference(where, "missing", expected=value))
        found.extend(
            Difference(f"{path}.{key}", "unexpected", got=value)
            for key, value in got.items()
            if key not in expected
        )
        return found
    if isinstance(expected, list) and isinstance(got, list):
        return _list_differences(expected, got, path)
    return [Difference(path, "differs", expected, got)]


def _comparable(expected: Any, got: Any) -> bool:
    """Worth comparing field by field: two records of one kind (the same ``type``), or two lists."""
    if isinstance(expected, dict) and isinstance(got, dict):
        return expected.get("type") == got.get("type")
    return isinstance(expected, list) and isinstance(got, list)


def _list_differences(expected: Sequence[Any], got: Sequence[Any], path: str) -> list[Difference]:
    """Along :func:`align`: a run of missing items next to a run of unexpected ones is paired item by
    item (a record with one wrong field is one difference, not a missing and an unexpected record)."""
    found: list[Difference] = []
    missing: list[int] = []
    unexpected: list[int] = []

    def settle() -> None:
        paired = min(len(missing), len(unexpected))
        for i, j in zip(missing[:paired], unexpected[:paired], strict=True):
            where = f"{path}[{j}]"
            if _comparable(expected[i], got[j]):
                found.extend(differences(expected[i], got[j], where))
            else:
                found.append(Difference(where, "differs", expected[i], got[j]))
        found.extend(Difference(f"{path}[{i}]", "missing", expected=expected[i]) for i in missing[paired:])
        found.extend(Difference(f"{path}[{j}]", "unexpected", got=got[j]) for j in unexpected[paired:])
        missing.clear()
        unexpected.clear()

    for mark, i, j in _aligned(expected, got):
        if mark == "-":
            missing.append(i)
        elif mark == "+":
            unexpected.append(j)
        else:
            settle()
    settle()
    return found


def _aligned(expected: Sequence[Any], got: Sequence[Any]) -> list[tuple[str, int, int]]:
    """The two lists as one sequence diff along a longest common subsequence under :func:`matches`:
    ``("=", i, j)`` both sides, ``("-", i, j)`` expected item ``i`` absent, ``("+", i, j)`` item ``j``
    not expected (the other index is where the walk stood)."""
    rows, cols = len(expected), len(got)
    best = [[0] * (cols + 1) for _ in range(rows + 1)]
    for i in range(rows - 1, -1, -1):
        for j in range(cols - 1, -1, -1):
            if matches(expected[i], got[j]):
                best[i][j] = best[i + 1][j + 1] + 1
            else:
                best[i][j] = max(best[i + 1][j], best[i][j + 1])
    entries: list[tuple[str, int, int]] = []
    i = j = 0
    while i < rows or j < cols:
        if i < rows and j < cols and matches(expected[i], got[j]) and best[i][j] == best[i + 1][j + 1] + 1:
            entries.append(("=", i, j))
            i, j = i + 1, j + 1
        elif i < rows and (j == cols or best[i + 1][j] >= best[i][j + 1]):
            entries.append(("-", i, j))
            i += 1
        else:
            entries.append(("+", i, j))
            j += 1
    return entries


def align(expected: Sequence[Any], got: Sequence[Any]) -> list[tuple[str, Any]]:
    """The two output lists as one sequence diff under :func:`matches`: ``("=", got)``,
    ``("-", expected)`` and ``("+", got)`` entries, along a longest common subsequence."""
    return [(mark, expected[i] if mark == "-" else got[j]) for mark, i, j in _aligned(expected, got)]
