"""Field factories shared by the wire mirrors and the machine inputs.

Each factory returns an ``attrs.field`` whose converter checks the value against
one wire type and raises :class:`~dynevent.errors.InvalidMessage` naming the
owning class, the field and the value.  The wire type is recorded in the
field's metadata under :data:`WIRE_KEY`, for conversion and for strategies.
"""

from __future__ import annotations

import math
import struct
import sys
from collections.abc import Callable, Iterable, Mapping
from enum import Enum
from typing import Any, TypeVar, cast

import attrs

from dynevent.errors import InvalidValue

#: The largest uint32: run seqs and log seqs wrap from it to 0.
U32_MAX = 2**32 - 1
#: The largest uint64: event ids wrap from it to 0 (an adapter's ids).
U64_MAX = 2**64 - 1
#: Nanoseconds in a second: every instant (``now``) is integer nanoseconds since the Unix epoch.
SECOND = 1_000_000_000


def seq_after(seq: int, than: int) -> bool:
    """Serial-number order of uint32 seqs (RFC 1982): is run ``seq`` after run ``than``?"""
    return 0 < ((seq - than) & U32_MAX) < 2**31


def id_not_after(first: int, second: int) -> bool:
    """Is id ``first`` at or before ``second``?  Ids rise in a run, modulo 2**64 (an adapter's ids wrap)."""
    return (second - first) & U64_MAX < 2**63


#: Field metadata key of an annotation: a field that is not part of the value
#: (no equality, not encoded), such as the rule an output carries.
ANNOTATION = "dynevent.annotation"

#: The one NaN every float32 field stores (NaN payloads are not kept).
CANONICAL_NAN = float("nan")
_F32 = struct.Struct("<f")


def _owner(instance: object) -> str:
    return type(instance).__name__


def _integer(low: int, high: int, wire: str) -> attrs.Converter[Any, Any]:
    def convert(value: Any, instance: object, field: attrs.Attribute[Any]) -> int:
        if type(value) is not int:
            if isinstance(value, bool) or not isinstance(value, int):
                raise InvalidValue(_owner(instance), field.name, value, f"expected an integer ({wire})")
            value = int(value)  # an IntEnum member is stored as its plain value
        if not low <= value <= high:
            raise InvalidValue(
                _owner(instance), field.name, value, f"out of range for {wire} [{low}, {high}]"
            )
        checked: int = value
        return checked

    return attrs.Converter(convert, takes_self=True, takes_field=True)


def _float32(value: Any, instance: object, field: attrs.Attribute[Any]) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InvalidValue(_owner(instance), field.name, value, "expected a number (float32)")
    try:
        rounded: float = _F32.unpack(_F32.pack(value))[0]
    except (OverflowError, struct.error):
        raise InvalidValue(
            _owner(instance), field.name, value, "out of range for float32 (magnitude above 3.4028235e38)"
        ) from None
    return CANONICAL_NAN if math.isnan(rounded) else rounded


def string_problem(value: str) -> str | None:
    """Why ``value`` cannot travel as a wire string (R1.2), or None."""
    if not value.isascii():
        try:
            value.encode("utf-8")
        except UnicodeEncodeError as exc:
            return f"not UTF-8 encodable (lone surrogate at index {exc.start})"
    if "\x00" in value:
        return f"NUL character at index {value.index(chr(0))}"
    return None


def check_string(value: Any, instance: object, field: attrs.Attribute[Any]) -> str:
    """Check ``value`` as a wire string for ``field`` of ``instance``; return it as a plain ``str``."""
    if type(value) is not str:
        if not isinstance(value, str):
            raise InvalidValue(_owner(instance), field.name, value, "expected a string")
        value = value.value if isinstance(value, Enum) else str.__str__(value)
    problem = string_problem(value)
    if problem is not None:
        raise InvalidValue(_owner(instance), field.name, value, problem)
    return cast(str, value)


def _boolean(value: Any, instance: object, field: attrs.Attribute[Any]) -> bool:
    if type(value) is not bool:
        raise InvalidValue(_owner(instance), field.name, value, "expected a bool")
    return value


def _nested(cls: type[Any]) -> attrs.Converter[Any, Any]:
    def convert(value: Any, instance: object, field: attrs.Attribute[Any]) -> Any:
        if type(value) is not cls:
            raise InvalidValue(_owner(instance), field.name, value, f"expected a {cls.__name__}")
        return value

    return attrs.Converter(convert, takes_self=True, takes_field=True)


def _array(cls: type[Any]) -> attrs.Converter[Any, Any]:
    def convert(value: Any, instance: object, field: attrs.Attribute[Any]) -> tuple[Any, ...]:
        if type(value) is not tuple:
            if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Iterable):
                raise InvalidValue(
                    _owner(instance), field.name, value, f"expected a sequence of {cls.__name__}"
                )
            value = tuple(value)
        for index, item in enumerate(value):
            if type(item) is not cls:
                raise InvalidValue(
                    _owner(instance), f"{field.name}[{index}]", item, f"expected a {cls.__name__}"
                )
        return cast("tuple[Any, ...]", value)

    return attrs.Converter(convert, takes_self=True, takes_field=True)


def _wrap(function: Callable[[Any, object, attrs.Attribute[Any]], Any]) -> attrs.Converter[Any, Any]:
    return attrs.Converter(function, takes_self=True, takes_field=True)


WIRE_KEY = "dynevent.wire"
_INTEGER_RANGES = {
    "uint8": (0, 2**8 - 1),
    "uint32": (0, U32_MAX),
    "uint64": (0, U64_MAX),
    "int32": (-(2**31), 2**31 - 1),
    "int64": (-(2**63), 2**63 - 1),
}
_CONVERTERS: dict[str, attrs.Converter[Any, Any]] = {
    **{wire: _integer(low, high, wire) for wire, (low, high) in _INTEGER_RANGES.items()},
    "float32": _wrap(_float32),
    "string": _wrap(check_string),
    "bool": _wrap(_boolean),
}


def _float_key(value: float) -> float | None:
    """Equality key of a float32 field: every NaN is one value, as on the wire."""
    return None if math.isnan(value) else value


#: Field metadata key of a fast check: a Python expression over ``{v}`` that is true only for values
#: the field's converter would return unchanged (see :func:`fast_init`).
FAST_KEY = "dynevent.fast"


def integer_check(low: int, high: int) -> str:
    """The fast check of an integer field of range [low, high]."""
    return f"type({{v}}) is int and {low} <= {{v}} <= {high}"


#: The fast check of a wire string: ASCII without NUL is always valid UTF-8 for the wire (R1.2).
STRING_CHECK = "type({v}) is str and {v}.isascii() and '\\x00' not in {v}"

_FAST_CHECKS = {
    **{wire: integer_check(*bounds) for wire, bounds in _INTEGER_RANGES.items()},
    "string": STRING_CHECK,
    "bool": "type({v}) is bool",
    "float32": "type({v}) is float and {v} == 0.0",  # the default; any other float is rounded to float32
}


def scalar(wire: str, default: Any) -> Any:
    eq_key = _float_key if wire == "float32" else True
    metadata: dict[str, Any] = {WIRE_KEY: wire}
    if wire in _FAST_CHECKS:
        metadata[FAST_KEY] = _FAST_CHECKS[wire]
    return attrs.field(default=default, converter=_CONVERTERS[wire], eq=eq_key, metadata=metadata)


def u8(default: int = 0) -> Any:
    return scalar("uint8", default)


def u32(default: int = 0) -> Any:
    return scalar("uint32", default)


def u64(default: int = 0) -> Any:
    return scalar("uint64", default)


def i32(default: int = 0) -> Any:
    return scalar("int32", default)


def i64(default: int = 0) -> Any:
    return scalar("int64", default)


def f32(default: float = 0.0) -> Any:
    return scalar("float32", default)


def string(default: str = "") -> Any:
    return scalar("string", default)


def boolean_field(default: bool = False) -> Any:
    return scalar("bool", default)


def message(cls: type[Any]) -> Any:
    return attrs.field(
        factory=cls,
        converter=_nested(cls),
        metadata={WIRE_KEY: cls, FAST_KEY: f"type({{v}}) is _{cls.__name__}"},
    )


def sequence(cls: type[Any]) -> Any:
    return attrs.field(
        factory=tuple,
        converter=_array(cls),
        metadata={WIRE_KEY: (cls,), FAST_KEY: "type({v}) is tuple and not {v}"},
    )


# --------------------------------------------------------------------------- generated constructors
#
# One mechanism, four uses.  attrs' own ``__init__`` and ``attrs.evolve`` run every converter and
# validator again, which the machine's hot steps need not pay for values it built from state already
# checked (a progress step takes about 2.7 us with what follows: bench/run.py, workload 2s).  So
# :func:`_generate` compiles, once per class, a plain function that makes the instance with
# ``object.__new__`` and sets each slot through its descriptor (past the frozen ``__setattr__``):
#
# - :func:`fast_init`: the class's ``__init__``, which still converts any value its cheap check
#   does not pass, so construction from outside keeps attrs' checks and messages exactly;
# - :func:`maker`: a keyword constructor with no checks, for values built from checked state;
# - :func:`replacer`: ``attrs.evolve`` without ``__init__``, keyword changes;
# - :func:`copier`: the same, for one step that always changes the same fields, positionally.
#
# tests/wire/test_fast_init.py holds each to attrs' own behaviour.

_T = TypeVar("_T")
_C = TypeVar("_C", bound=type)
_FACTORY: Any = type(attrs.Factory(list))
_KEEP: Any = object()  # "no change" marker of generated replace functions


def _slot_setter(cls: type, name: str) -> Any:
    """The setter of slot ``name`` of ``cls``, past the frozen ``__setattr__`` (a base class may own it)."""
    owner = next(klass for klass in cls.__mro__ if name in klass.__dict__)
    return owner.__dict__[name].__set__


def _generate(cls: type, name: str, signature: str, body: list[str]) -> Any:
    """Compile a function over ``cls``'s fields that sets slots through their descriptors."""
    names = [field.name for field in attrs.fields(cls)]
    namespace: dict[str, Any] = {"_new": object.__new__, "_cls": cls, "_KEEP": _KEEP}
    for field in names:
        namespace[f"_set_{field}"] = _slot_setter(cls, field)
    source = "\n".join(
        [f"def {name}({signature.format(names=names)}):", "    new = _new(_cls)", *body, "    return new"]
    )
    exec(source, namespace)
    return namespace[name]


def maker(cls: type[_T]) -> Callable[..., _T]:
    """A keyword-only constructor for ``cls`` that skips converters and validators.

    For values the machine builds from state it has already checked; every
    field must be given.
    """
    names = [field.name for field in attrs.fields(cls)]  # type: ignore[arg-type]
    body = [f"    _set_{field}(new, {field})" for field in names]
    function: Callable[..., _T] = _generate(cls, "make", "*, " + ", ".join(names), body)
    return function


def fast_init(cls: _C) -> _C:
    """Give an attrs class an ``__init__`` that sets its slots directly, skipping a field's converter
    when its fast check passes.

    A class decorator, applied above ``@attrs.frozen`` (slotted, no validators).  Each field whose
    metadata has a :data:`FAST_KEY` check takes a value that passes it as it
    is (the check accepts only values the converter would return unchanged);
    any other value goes through the field's converter, so the checks and the
    error messages are exactly attrs' own.  Fields without a check always go
    through their converter.  Defaults and factories are kept.
    """
    fields = attrs.fields(cls)
    # a check may name the module's globals (a vocabulary set, a class)
    namespace: dict[str, Any] = dict(vars(sys.modules[cls.__module__]))
    namespace.update(_cls=cls, _NOTHING=attrs.NOTHING)
    params: list[str] = []
    body: list[str] = []
    for field in fields:
        name = field.name
        if field.validator is not None or not field.init:
            raise TypeError(f"fast_init: {cls.__name__}.{name} must be an init field without validator")
        namespace[f"_set_{name}"] = _slot_setter(cls, name)
        namespace[f"_field_{name}"] = field
        default = field.default
        if default is attrs.NOTHING:
            params.append(name)
        elif isinstance(default, _FACTORY):
            namespace[f"_factory_{name}"] = default.factory
            params.append(f"{name}=_NOTHING")
            body.append(f"    if {name} is _NOTHING: {name} = _factory_{name}()")
        else:
            namespace[f"_default_{name}"] = default
            params.append(f"{name}=_default_{name}")
        converter = field.converter
        if converter is not None:
            call = _converter_call(converter, name, namespace)
            check = field.metadata.get(FAST_KEY)
            if isinstance(field.metadata.get(WIRE_KEY), type):
                namespace[f"_{field.metadata[WIRE_KEY].__name__}"] = field.metadata[WIRE_KEY]
            if check is None:
                body.append(f"    {name} = {call}")
            else:
                body.append(f"    if not ({check.format(v=name)}): {name} = {call}")
        body.append(f"    _set_{name}(self, {name})")
    positional = [param for param, field in zip(params, fields, strict=True) if not field.kw_only]
    keywords = [param for param, field in zip(params, fields, strict=True) if field.kw_only]
    signature = ", ".join(["self", *positional, *(["*", *keywords] if keywords else [])])
    source = "\n".join([f"def __init__({signature}):", *body])
    exec(compile(source, f"<fast init of {cls.__qualname__}>", "exec"), namespace)
    init = namespace["__init__"]
    init.__qualname__ = f"{cls.__qualname__}.__init__"
    init.__doc__ = vars(cls)["__init__"].__doc__
    cls.__init__ = init  # type: ignore[misc]
    return cls


def _converter_call(converter: Any, name: str, namespace: dict[str, Any]) -> str:
    """The call of ``converter`` on the local ``name`` in a generated ``__init__``."""
    if isinstance(converter, attrs.Converter):
        namespace[f"_convert_{name}"] = converter.converter  # type: ignore[attr-defined]
        arguments = [name]
        if converter.takes_self:  # type: ignore[attr-defined]
            arguments.append("self")
        if converter.takes_field:  # type: ignore[attr-defined]
            arguments.append(f"_field_{name}")
        return f"_convert_{name}({', '.join(arguments)})"
    namespace[f"_convert_{name}"] = converter
    return f"_convert_{name}({name})"


def copier(cls: type[_T], *changed: str) -> Callable[..., _T]:
    """A copy function for one slotted class that takes new values of ``changed``, positionally.

    ``copy(instance, *values)`` copies every other slot as it is: for a step that always changes
    the same fields, cheaper than :func:`replacer`'s keyword arguments and their "no change" tests.
    """
    names = [field.name for field in attrs.fields(cls)]  # type: ignore[arg-type]
    unknown = set(changed) - set(names)
    if unknown:
        raise TypeError(f"copier: {cls.__name__} has no fields {sorted(unknown)}")
    body = [f"    _set_{field}(new, {field if field in changed else 'self.' + field})" for field in names]
    function: Callable[..., _T] = _generate(cls, "copy", ", ".join(["self", *changed]), body)
    return function


def replacer(cls: type[_T]) -> Callable[..., _T]:
    """A fast ``attrs.evolve`` for one slotted class: keyword-only changes, no ``__init__``.

    Generated once per class: ``replace(instance, field=value, ...)`` copies
    every slot, taking the given values instead where there are some.
    """
    names = [field.name for field in attrs.fields(cls)]  # type: ignore[arg-type]
    body = [f"    _set_{field}(new, self.{field} if {field} is _KEEP else {field})" for field in names]
    signature = "self, /, *, " + ", ".join(f"{field}=_KEEP" for field in names)
    function: Callable[..., _T] = _generate(cls, "replace", signature, body)
    return function
