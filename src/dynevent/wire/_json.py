"""Strict, bounded JSON reading shared by every parser at the edge.

Python's :func:`json.loads` can raise several unrelated exception types on
hostile text (``RecursionError`` for deep nesting, ``ValueError`` for integers
with too many digits, ``UnicodeDecodeError`` for bad bytes).  :func:`parse`
turns every one of them into a single :class:`JsonProblem` carrying a readable
sentence, and refuses duplicate object keys, which JSON leaves undefined.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from typing import Any

__all__ = ["MAX_DEPTH", "JsonProblem", "dumps", "parse"]

#: Deepest nesting of arrays and objects accepted in any JSON text.
MAX_DEPTH = 64


class JsonProblem(Exception):
    """Raised by :func:`parse`; callers wrap it in their own located error."""


def _pairs(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    result = dict(pairs)
    if len(result) != len(pairs):  # a key came twice: name the first one that did
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                raise JsonProblem(f"duplicate key {key!r}")
            seen.add(key)
    return result


#: One decoder for every parse (``json.loads`` with a hook builds a new one each call); its scanner is
#: called directly, with the whitespace handling of ``JSONDecoder.decode`` around it.
_DECODER = json.JSONDecoder(object_pairs_hook=_pairs)
_SCAN: Callable[[str, int], tuple[Any, int]] = vars(_DECODER)["scan_once"]
_SPACE = re.compile(r"[ \t\n\r]*").match  # JSON's whitespace, as json.decoder.WHITESPACE matches it
_BLANK = frozenset(" \t\n\r")


def _skip_space(text: str, index: int) -> int:
    """The index of the first character at or after ``index`` that is not JSON whitespace."""
    match = _SPACE(text, index)
    return index if match is None else match.end()


def _decode(text: str) -> Any:
    """``_DECODER.decode(text)``: the same values and the same errors, without its two Python layers."""
    index = _skip_space(text, 0) if text and text[0] in _BLANK else 0
    try:
        value, end = _SCAN(text, index)
    except StopIteration as stop:
        raise json.JSONDecodeError("Expecting value", text, stop.value) from None
    if end != len(text):
        end = _skip_space(text, end)
        if end != len(text):
            raise json.JSONDecodeError("Extra data", text, end)
    return value


def _depth_ok(value: Any) -> bool:
    """Is the nesting of arrays and objects in ``value`` within MAX_DEPTH?  (Iterative: containers only.)"""
    pending: list[tuple[Any, int]] = [(value, 1)] if isinstance(value, (dict, list)) else []
    while pending:
        container, depth = pending.pop()
        if depth > MAX_DEPTH:
            return False
        items = container.values() if isinstance(container, dict) else container
        pending.extend((item, depth + 1) for item in items if isinstance(item, (dict, list)))
    return True


def parse(text: str | bytes | bytearray, *, bounded: bool = True) -> Any:
    """Parse JSON text strictly; raise :class:`JsonProblem` on any fault.

    ``NaN``, ``Infinity`` and ``-Infinity`` are accepted, as Python's and
    rosbridge's encoders write them for non-finite floats.  ``bounded=False``
    skips the walk that refuses nesting deeper than :data:`MAX_DEPTH` (text
    far deeper is still refused): for callers that decode the value against
    a schema of bounded depth, which refuses any other nesting anyway.
    """
    if isinstance(text, (bytes, bytearray)):
        try:
            text = bytes(text).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise JsonProblem(f"not UTF-8 text (byte {exc.start})") from None
    if not isinstance(text, str):
        raise JsonProblem(f"expected JSON text, got {type(text).__name__}")
    try:
        value = _decode(text)
    except JsonProblem:
        raise
    except json.JSONDecodeError as exc:
        raise JsonProblem(f"not valid JSON: {exc.msg} at line {exc.lineno} column {exc.colno}") from None
    except RecursionError:  # far deeper than the limit: the decoder gave up first
        raise JsonProblem(f"nested deeper than {MAX_DEPTH} levels") from None
    except ValueError as exc:
        raise JsonProblem(f"not valid JSON: {exc}") from None
    # only a text with more brackets than the limit can be too deep; then walk the parsed containers
    if (
        bounded
        and len(text) > MAX_DEPTH
        and text.count("[") + text.count("{") > MAX_DEPTH
        and not _depth_ok(value)
    ):
        raise JsonProblem(f"nested deeper than {MAX_DEPTH} levels")
    return value


def utf8_size(text: str) -> int:
    """The length of ``text`` in UTF-8 bytes: the one unit of every description limit."""
    return len(text) if text.isascii() else len(text.encode("utf-8", "surrogatepass"))


def dumps_sorted(value: Any) -> str:
    """Write compact JSON text with keys sorted at every level."""
    return json.dumps(value, separators=(",", ":"), ensure_ascii=False, sort_keys=True)


def dumps(value: Any) -> str:
    """Write compact JSON text keeping the order of keys."""
    return json.dumps(value, separators=(",", ":"), ensure_ascii=False)
