"""Why a description fails its schema: the ``jsonschema`` package's errors, as short lines with paths.

Each line is ``<JSON pointer>: <what is wrong>`` (``/one_of/1: 5.5 is not a
place``; the description itself is ``/``).  Where a ``oneOf`` fails, the line
follows the one form that got furthest (its errors all lie deeper than the
``oneOf``): ``{"place": "A", "followed_by": [1.5]}`` is explained at
``/followed_by/0``, not as "not a go_to_place description".  When no form got
further than another, the line names what was expected: the schema's title.
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Iterable, Sequence
from typing import Any

import attrs

from dynevent.errors import integer_text

__all__ = ["explain", "pointer", "prefixed", "render", "under", "writable"]

#: Values longer than this are shortened in an error line.
_LONGEST_VALUE = 48

_ARTICLES = {
    "object": "an object",
    "array": "an array",
    "string": "a string",
    "integer": "an integer",
    "number": "a number",
    "boolean": "a boolean",
    "null": "null",
}


def pointer(path: Iterable[Any]) -> str:
    """The JSON pointer of a path (``/`` for the description itself)."""
    parts = [str(part).replace("~", "~0").replace("/", "~1") for part in path]
    return "/" + "/".join(parts)


def render(value: Any) -> str:
    """A value as compact JSON, shortened past :data:`_LONGEST_VALUE` characters.

    The cost is bounded whatever the value: only the pieces up to the cut are written (a
    description of a megabyte is not encoded to show its first 48 characters), an integer too
    long to write is named by its length, and nesting of any depth is walked without recursion.
    """
    pieces: list[str] = []
    size = 0
    pending: list[Any] = [value]
    while pending and size <= _LONGEST_VALUE:
        item = pending.pop()
        if isinstance(item, _Piece):
            piece = item.text
        elif isinstance(item, dict):
            piece = "{"
            pending.append(_Piece("}"))
            for number, (key, member) in reversed(list(enumerate(_first(item.items())))):
                pending.extend((member, _Piece(_scalar(str(key)) + ": ")))
                if number:
                    pending.append(_Piece(", "))
        elif isinstance(item, (list, tuple)):
            piece = "["
            pending.append(_Piece("]"))
            for number, member in reversed(list(enumerate(_first(item)))):
                pending.append(member)
                if number:
                    pending.append(_Piece(", "))
        else:
            piece = _scalar(item)
        pieces.append(piece)
        size += len(piece)
    text = "".join(pieces)
    return text if len(text) <= _LONGEST_VALUE else text[: _LONGEST_VALUE - 1] + "…"


@attrs.frozen
class _Piece:
    """Text already written, waiting on :func:`render`'s stack."""

    text: str


def _first(items: Iterable[Any]) -> list[Any]:
    """The members a shortened rendering can show (each takes at least one character)."""
    return list(itertools.islice(items, _LONGEST_VALUE))


class _LongInteger(int):
    """An integer too long to write, that names its length where a message would write it."""

    def __repr__(self) -> str:
        return integer_text(self)

    __str__ = __repr__


def writable(value: Any) -> Any:
    """``value`` (parsed JSON) with each integer too long to write standing in for itself as one that
    names its length (:func:`~dynevent.errors.integer_text`): what the ``jsonschema`` package, which
    writes the values at fault into its messages, is given.  ``value`` itself when it holds none.
    Nesting of any depth is walked without recursion; a tuple stays a tuple."""
    top: list[Any] = [value]
    pending: list[tuple[Any, Any]] = [(top, 0)]
    tuples: list[tuple[Any, Any]] = []
    changed = False
    while pending:
        holder, key = pending.pop()
        item = holder[key]
        if type(item) is int and integer_text(item).startswith("<"):
            holder[key], changed = _LongInteger(item), True
        elif isinstance(item, dict):
            holder[key] = dict(item)
            pending.extend((holder[key], name) for name in item)
        elif isinstance(item, (list, tuple)):
            holder[key] = list(item)
            pending.extend((holder[key], index) for index in range(len(item)))
            if isinstance(item, tuple):
                tuples.append((holder, key))
    for holder, key in reversed(tuples):  # the inner ones first
        holder[key] = tuple(holder[key])
    return top[0] if changed else value


def _scalar(value: Any) -> str:
    if isinstance(value, bool) or value is None:
        return "true" if value is True else ("false" if value is False else "null")
    if isinstance(value, int):
        return integer_text(value)
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, str):
        return json.dumps(value[: _LONGEST_VALUE + 1], ensure_ascii=False)
    if isinstance(value, float):
        return float.__repr__(value)
    return repr(value)[: _LONGEST_VALUE + 1]  # not JSON (never from a parsed description)


def _title(schema: Any, fallback: str) -> str:
    title = schema.get("title") if isinstance(schema, dict) else None
    return title if isinstance(title, str) else fallback


#: (the path of the value at fault, what is wrong with it, whether it is the value's very kind that is
#: wrong: a type, or none of a ``oneOf``'s forms)
Line = tuple[tuple[Any, ...], str, bool]


def _line(error: Any) -> Line:
    """One error (a ``oneOf``/``anyOf`` is handled by :func:`_explain_one`)."""
    path = tuple(error.absolute_path)
    value = render(error.instance)
    kind = error.validator
    if kind == "type":
        expected = error.validator_value
        names = [expected] if isinstance(expected, str) else list(expected)
        return path, f"{value} is not {' or '.join(_ARTICLES.get(name, name) for name in names)}", True
    if kind == "required":
        missing = [name for name in error.validator_value if name not in error.instance]
        return path, f"{', '.join(json.dumps(name) for name in missing)} is required", False
    if kind == "minItems":
        count = error.validator_value
        return path, f"{value} has fewer than {count} item{'s' if count != 1 else ''}", False
    if kind == "minimum":
        return path, f"{value} is less than {error.validator_value}", False
    return path, error.message, False


def _explain_one(error: Any) -> list[Line]:
    if error.validator not in ("oneOf", "anyOf"):
        return [_line(error)]
    path = tuple(error.absolute_path)
    title = _title(error.schema, "any of its forms")
    if not error.context:  # a oneOf that more than one form matched
        return [(path, f"{render(error.instance)} is not {title}: it fits more than one of its forms", False)]
    branches: dict[Any, list[Any]] = {}
    for sub in error.context:
        branches.setdefault(sub.relative_schema_path[0], []).append(sub)
    explained = [_explain_all(errors) for errors in branches.values()]
    # The form to explain by: the one that got further (all that is wrong lies deeper than the
    # value), else the one whose kind the value has (what is wrong is not the value's kind).
    further = [lines for lines in explained if all(len(where) > len(path) for where, _, _ in lines)]
    if len(further) == 1:
        return further[0]
    kind = [lines for lines in explained if not any(wrong and where == path for where, _, wrong in lines)]
    if not further and len(kind) == 1:
        return kind[0]
    return [(path, f"{render(error.instance)} is not {title}", True)]


def _explain_all(errors: Iterable[Any]) -> list[Line]:
    lines: dict[Line, None] = {}
    for error in errors:
        for line in _explain_one(error):
            lines.setdefault(line, None)
    return list(lines)


def explain(errors: Iterable[Any]) -> tuple[str, ...]:
    """The lines of a description's errors (``jsonschema`` ``ValidationError``\\ s), each once, in order."""
    return tuple(f"{pointer(path)}: {text}" for path, text, _ in _explain_all(errors))


def prefixed(prefix: Sequence[Any], lines: Iterable[str]) -> tuple[str, ...]:
    """``lines`` of a nested description, their pointers moved under ``prefix`` (a line of another
    validator that has no pointer is put at the nested description itself)."""
    head = pointer(prefix)
    return tuple(under(head, str(line)) for line in lines)


def under(head: str, line: str) -> str:
    """One line of a nested description, its pointer moved under ``head`` (a pointer)."""
    if line.startswith("/:"):
        return head + line[1:]
    if line.startswith("/"):
        return head + line
    return f"{head}: {line}"
