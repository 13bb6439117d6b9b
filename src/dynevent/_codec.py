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
from typing import Any, Union

import attrs

from ._fields import string_problem
from .errors import DyneventError
from .messages import WireMessage

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
        return {field.name: encode(getattr(value, field.name)) for field in attrs.fields(type(value))}
    if isinstance(value, (tuple, list)):
        return [encode(item) for item in value]
    if isinstance(value, dict):
        return {str(key): encode(item) for key, item in value.items()}
    raise TypeError(f"cannot encode {type(value).__name__}")


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _describe(tp: Any) -> str:
    return getattr(tp, "__name__", None) or str(tp)


def decode(tp: Any, data: Any, path: str = "$") -> Any:
    """A value of type ``tp`` built from the plain JSON ``data``."""
    origin = typing.get_origin(tp)
    if tp is Any:
        return data
    if origin in (Union, types.UnionType):
        options = typing.get_args(tp)
        if data is None and type(None) in options:
            return None
        errors = []
        for option in options:
            if option is type(None):
                continue
            try:
                return decode(option, data, path)
            except CodecError as exc:
                errors.append(exc)
        raise errors[0] if len(errors) == 1 else CodecError(path, f"expected {_describe(tp)}")
    if origin is tuple:
        if not isinstance(data, list):
            raise CodecError(path, f"expected an array, got {type(data).__name__}")
        item_type = typing.get_args(tp)[0]
        return tuple(decode(item_type, item, f"{path}[{index}]") for index, item in enumerate(data))
    if tp is type(None):
        if data is not None:
            raise CodecError(path, "expected null")
        return None
    if tp is bool:
        if type(data) is not bool:
            raise CodecError(path, f"expected a boolean, got {type(data).__name__}")
        return data
    if tp is int:
        if type(data) is not int:
            raise CodecError(path, f"expected an integer, got {type(data).__name__}")
        return data
    if tp is float:
        if isinstance(data, bool) or not isinstance(data, (int, float)):
            raise CodecError(path, f"expected a number, got {type(data).__name__}")
        try:
            return float(data)
        except OverflowError:  # an integer of any size may arrive where a float is expected
            raise CodecError(path, "an integer out of range for a float") from None
    if tp is str:
        if type(data) is not str:
            raise CodecError(path, f"expected a string, got {type(data).__name__}")
        problem = string_problem(data)
        if problem is not None:
            raise CodecError(path, problem)
        return data
    if isinstance(tp, type) and issubclass(tp, enum.Enum):
        try:
            return tp(data)
        except (ValueError, TypeError):
            raise CodecError(path, f"expected one of {[member.value for member in tp]}") from None
    if isinstance(tp, type) and issubclass(tp, WireMessage):
        try:
            return tp.from_dict(data)
        except DyneventError as exc:
            raise CodecError(path, str(exc)) from None
    if isinstance(tp, type) and attrs.has(tp):
        return _decode_attrs(tp, data, path)
    raise CodecError(path, f"cannot decode {_describe(tp)}")


def _decode_attrs(cls: type, data: Any, path: str) -> Any:
    if not isinstance(data, dict):
        raise CodecError(path, f"expected an object for {cls.__name__}, got {type(data).__name__}")
    fields = attrs.fields_dict(cls)
    hints = _hints(cls)
    values: dict[str, Any] = {}
    for key, raw in data.items():
        if key not in fields:
            raise CodecError(f"{path}.{key}", f"unknown field of {cls.__name__}")
        values[key] = decode(hints[key], raw, f"{path}.{key}")
    for name, field in fields.items():
        if name not in values and field.default is attrs.NOTHING:
            raise CodecError(f"{path}.{name}", f"missing field of {cls.__name__}")
    try:
        return cls(**values)
    except DyneventError as exc:
        raise CodecError(path, str(exc)) from None
