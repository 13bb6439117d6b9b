"""Plain-JSON encoding of dynevent's frozen values, and typed decoding back.

``encode`` turns any state, input, output or wire message into plain JSON
values.  ``decode`` rebuilds a value of a given type from them, guided by the
type annotations of the attrs classes, and raises :class:`CodecError` with a
JSON path on any mismatch.  Range checks belong to the classes themselves
(wire messages and inputs check on construction); decoding only checks shape.
"""

from __future__ import annotations

import enum
import functools
import types
import typing
from typing import Any, TypeAlias, Union

import attrs

from dynevent.errors import DyneventError
from dynevent.wire._fields import ANNOTATION, string_problem
from dynevent.wire.messages import WireMessage

__all__ = ["CodecError", "decode", "encode"]


class CodecError(Exception):
    """A JSON value does not fit the expected type; ``path`` says where."""

    def __init__(self, path: str, problem: str) -> None:
        self.path = path
        self.problem = problem
        super().__init__(f"{path}: {problem}")


def encode(value: Any) -> Any:
    """Plain JSON values for ``value`` (attrs classes become objects keyed by field name)."""
    if value is None or (isinstance(value, (bool, int, str)) and not isinstance(value, enum.Enum)):
        return value
    if isinstance(value, enum.Enum):
        return value.value
    if isinstance(value, float):
        return value
    if isinstance(value, WireMessage):
        return value.to_dict()
    if attrs.has(type(value)):
        return {name: encode(getattr(value, name)) for name in _encoded(type(value))}
    if isinstance(value, (tuple, list)):
        return [encode(item) for item in value]
    if isinstance(value, dict):
        return {str(key): encode(item) for key, item in value.items()}
    raise TypeError(f"cannot encode {type(value).__name__}")


_ENCODED: dict[type, tuple[str, ...]] = {}


def _encoded(cls: type) -> tuple[str, ...]:
    """The fields of an attrs class that encoding writes: all but the annotations (e.g. an output's rule)."""
    names = _ENCODED.get(cls)
    if names is None:
        names = _ENCODED[cls] = tuple(
            field.name for field in attrs.fields(cls) if not field.metadata.get(ANNOTATION)
        )
    return names


def _describe(tp: Any) -> str:
    return getattr(tp, "__name__", None) or str(tp)


#: Where a value sits: the root's name, then object keys and array indexes (made text only on error).
#: Where a value sits: the root's path, or ``(where of the parent, key or index)``, written out only
#: for an error (building a flat path for every value would cost more than decoding it).
_Where: TypeAlias = "str | tuple[_Where, str | int]"
_Decoder = typing.Callable[[Any, _Where], Any]


def _text(where: _Where) -> str:
    parts: list[str] = []
    while isinstance(where, tuple):
        where, part = where
        parts.append(f"[{part}]" if isinstance(part, int) else f".{part}")
    parts.append(where)
    return "".join(reversed(parts))


def decode(tp: Any, data: Any, path: str = "$") -> Any:
    """A value of type ``tp`` built from the plain JSON ``data``."""
    return _decoder(tp)(data, path)


@functools.cache
def _decoder(tp: Any) -> _Decoder:
    """The decoder of one type, built once: a fleet restore decodes thousands of states alike."""
    origin = typing.get_origin(tp)
    if tp is Any:
        return lambda data, where: data
    if origin in (Union, types.UnionType):
        return _union(tp)
    if origin is tuple:
        return _tuple(typing.get_args(tp)[0])
    if tp is type(None):
        return _none
    if tp is bool:
        return _bool
    if tp is int:
        return _int
    if tp is float:
        return _float
    if tp is str:
        return _str
    if isinstance(tp, type) and issubclass(tp, enum.Enum):
        return _enum(tp)
    if isinstance(tp, type) and issubclass(tp, WireMessage):
        return _message(tp)
    if isinstance(tp, type) and attrs.has(tp):
        return _attrs(tp)

    def cannot(data: Any, where: _Where) -> Any:
        raise CodecError(_text(where), f"cannot decode {_describe(tp)}")

    return cannot


def _union(tp: Any) -> _Decoder:
    optional = type(None) in typing.get_args(tp)
    options = [_decoder(option) for option in typing.get_args(tp) if option is not type(None)]

    def decode_union(data: Any, where: _Where) -> Any:
        if data is None and optional:
            return None
        errors = []
        for option in options:
            try:
                return option(data, where)
            except CodecError as exc:
                errors.append(exc)
        raise errors[0] if len(errors) == 1 else CodecError(_text(where), f"expected {_describe(tp)}")

    return decode_union


def _tuple(item_type: Any) -> _Decoder:
    item = _decoder(item_type)

    def decode_tuple(data: Any, where: _Where) -> Any:
        if not isinstance(data, list):
            raise CodecError(_text(where), f"expected an array, got {type(data).__name__}")
        return tuple(item(value, (where, index)) for index, value in enumerate(data))

    return decode_tuple


def _none(data: Any, where: _Where) -> None:
    if data is not None:
        raise CodecError(_text(where), "expected null")


def _bool(data: Any, where: _Where) -> bool:
    if type(data) is not bool:
        raise CodecError(_text(where), f"expected a boolean, got {type(data).__name__}")
    return data


def _int(data: Any, where: _Where) -> int:
    if type(data) is not int:
        raise CodecError(_text(where), f"expected an integer, got {type(data).__name__}")
    return data


def _float(data: Any, where: _Where) -> float:
    if isinstance(data, bool) or not isinstance(data, (int, float)):
        raise CodecError(_text(where), f"expected a number, got {type(data).__name__}")
    try:
        return float(data)
    except OverflowError:  # an integer of any size may arrive where a float is expected
        raise CodecError(_text(where), "an integer out of range for a float") from None


def _str(data: Any, where: _Where) -> str:
    if type(data) is not str:
        raise CodecError(_text(where), f"expected a string, got {type(data).__name__}")
    problem = string_problem(data)
    if problem is not None:
        raise CodecError(_text(where), problem)
    return data


#: The decoders that return a value of this exact type as it is (a string: when ASCII without NUL).
_KEPT: dict[_Decoder, type] = {_int: int, _bool: bool, _str: str}


def _enum(tp: type[enum.Enum]) -> _Decoder:
    def decode_enum(data: Any, where: _Where) -> Any:
        try:
            return tp(data)
        except (ValueError, TypeError):
            raise CodecError(_text(where), f"expected one of {[member.value for member in tp]}") from None

    return decode_enum


def _message(tp: type[WireMessage]) -> _Decoder:
    def decode_message(data: Any, where: _Where) -> Any:
        try:
            return tp.from_dict(data)
        except DyneventError as exc:
            raise CodecError(_text(where), str(exc)) from None

    return decode_message


def _attrs(cls: type) -> _Decoder:
    # what encoding writes, and nothing else: an annotation (an output's rule, a queued goal's kept
    # check) is never read from JSON
    fields = {name: field for name, field in attrs.fields_dict(cls).items() if name in _encoded(cls)}
    hints = typing.get_type_hints(cls)
    required = [name for name, field in fields.items() if field.default is attrs.NOTHING]
    decoders: dict[str, _Decoder] = {}

    def field_decoder(name: str) -> _Decoder:
        # built at first use: a class may hold itself (through an Optional), decoded lazily
        found = decoders.get(name)
        if found is None:
            found = decoders[name] = _decoder(hints[name])
        return found

    def decode_attrs(data: Any, where: _Where) -> Any:
        if not isinstance(data, dict):
            raise CodecError(
                _text(where), f"expected an object for {cls.__name__}, got {type(data).__name__}"
            )
        values: dict[str, Any] = {}
        for key, raw in data.items():
            decoder = decoders.get(key)
            if decoder is None:
                if key not in fields:
                    raise CodecError(_text((where, key)), f"unknown field of {cls.__name__}")
                decoder = field_decoder(key)
            kind = type(raw)
            if _KEPT.get(decoder) is kind and (kind is not str or (raw.isascii() and "\x00" not in raw)):
                values[key] = raw  # a value its decoder would return as it is: no call
            else:
                values[key] = decoder(raw, (where, key))
        for name in required:
            if name not in values:
                raise CodecError(_text((where, name)), f"missing field of {cls.__name__}")
        try:
            return cls(**values)
        except DyneventError as exc:
            raise CodecError(_text(where), str(exc)) from None

    return decode_attrs
