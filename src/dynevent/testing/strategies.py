"""Hypothesis strategies for every wire message, valid and hostile.

:func:`messages` derives a strategy for any wire class from its declared ROS
field types, so it stays in step with :mod:`dynevent.wire.messages` by construction.
Integers are drawn over their full range (hypothesis favours the boundaries),
float32 values include NaN, the infinities and subnormals, and strings range
over all of Unicode that the wire can carry.
"""

from __future__ import annotations

from typing import Any, TypeVar

from hypothesis import strategies as st

from dynevent.wire import messages as wire

__all__ = [
    "INTEGER_RANGES",
    "hostile_json_values",
    "json_values",
    "messages",
    "out_of_range_values",
    "wire_dicts",
    "wire_strings",
]

_M = TypeVar("_M", bound=wire.WireMessage)

#: Inclusive range of each integer wire type.
INTEGER_RANGES: dict[str, tuple[int, int]] = {
    "uint8": (0, 2**8 - 1),
    "uint32": (0, 2**32 - 1),
    "uint64": (0, 2**64 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "int64": (-(2**63), 2**63 - 1),
}

_BY_NAME: dict[str, type[wire.WireMessage]] = {cls.__name__: cls for cls in wire.MESSAGE_TYPES}


def wire_strings(max_size: int = 40) -> st.SearchStrategy[str]:
    """Text a wire string can carry: any Unicode but lone surrogates and NUL."""
    return st.text(
        alphabet=st.characters(exclude_categories=["Cs"], exclude_characters="\x00"),
        max_size=max_size,
    )


def _field_strategy(wire_type: str) -> st.SearchStrategy[Any]:
    if wire_type in INTEGER_RANGES:
        low, high = INTEGER_RANGES[wire_type]
        return st.integers(low, high)
    if wire_type == "float32":
        return st.floats(width=32, allow_nan=True, allow_infinity=True)
    if wire_type == "string":
        return wire_strings()
    if wire_type == "bool":
        return st.booleans()
    if wire_type.endswith("[]"):
        return st.lists(messages(_BY_NAME[wire_type[:-2]]), max_size=4)
    return messages(_BY_NAME[wire_type])


def messages(cls: type[_M]) -> st.SearchStrategy[_M]:
    """Every valid instance of the wire class ``cls``."""
    fields = {name: _field_strategy(kind) for name, kind in cls.wire_types().items()}
    return st.builds(cls, **fields)


def out_of_range_values(wire_type: str) -> st.SearchStrategy[Any]:
    """Values a field of ``wire_type`` must refuse (wrong type or outside the range)."""
    # every one of these is refused by every field kind, nested messages included
    wrong_types: st.SearchStrategy[Any] = st.one_of(
        st.none(), st.booleans(), st.lists(st.integers(), min_size=1, max_size=2), st.text(max_size=3)
    )
    if wire_type in INTEGER_RANGES:
        low, high = INTEGER_RANGES[wire_type]
        return st.one_of(
            wrong_types,
            st.integers(max_value=low - 1),
            st.integers(min_value=high + 1),
            st.floats(allow_nan=False),
            st.text(max_size=5),
        )
    if wire_type == "float32":
        too_big = float.fromhex("0x1.ffffffp+127")  # rounds past the largest float32
        return st.one_of(
            wrong_types,
            st.floats(min_value=too_big, allow_infinity=False),
            st.floats(max_value=-too_big, allow_infinity=False),
            st.integers(min_value=2**200),
            st.text(max_size=5),
        )
    if wire_type == "string":
        return st.one_of(
            st.none(),
            st.integers(),
            st.binary(max_size=5),
            st.text(max_size=5).map(lambda text: text + "\ud800"),
            st.text(max_size=5).map(lambda text: text + "\x00"),
        )
    if wire_type == "bool":
        return st.one_of(st.none(), st.integers(), st.text(max_size=3))
    return wrong_types


def json_values(max_leaves: int = 20) -> st.SearchStrategy[Any]:
    """Arbitrary JSON documents (finite numbers, Unicode keys and strings)."""
    scalars = st.one_of(
        st.none(),
        st.booleans(),
        st.integers(),
        st.floats(allow_nan=False, allow_infinity=False),
        st.text(max_size=10),
    )
    return st.recursive(
        scalars,
        lambda children: st.one_of(
            st.lists(children, max_size=4), st.dictionaries(st.text(max_size=8), children, max_size=4)
        ),
        max_leaves=max_leaves,
    )


def hostile_json_values(max_leaves: int = 20) -> st.SearchStrategy[Any]:
    """JSON-like values built to break parsers.

    Huge integers, NaN and infinities, lone surrogates, NUL, bools where
    integers belong, deep nesting and non-string keys.
    """
    scalars = st.one_of(
        st.none(),
        st.booleans(),
        st.integers(),
        st.integers(min_value=2**64 - 2, max_value=2**64 + 2),
        st.integers(min_value=10**40),
        st.floats(),
        st.text(max_size=10),
        st.sampled_from(["\ud800", "\udfff", "\x00", "\u2028", "\U0010ffff", "NaN", "-0"]),
    )
    return st.recursive(
        scalars,
        lambda children: st.one_of(
            st.lists(children, max_size=4),
            st.dictionaries(st.one_of(st.text(max_size=8), st.sampled_from(["id", "seq", "logs"])), children),
        ),
        max_leaves=max_leaves,
    )


def _plain(value: Any) -> Any:
    if isinstance(value, wire.WireMessage):
        return value.to_dict()
    if isinstance(value, list):
        return [_plain(item) for item in value]
    return value


def wire_dicts(cls: type[wire.WireMessage]) -> st.SearchStrategy[dict[str, Any]]:
    """Dicts shaped like ``cls`` with each field drawn from valid or hostile values."""
    fields = {
        name: st.one_of(
            _field_strategy(kind).map(
                lambda value: value.to_dict() if isinstance(value, wire.WireMessage) else value
            ),
            out_of_range_values(kind),
            hostile_json_values(max_leaves=5),
        )
        for name, kind in cls.wire_types().items()
    }
    return st.fixed_dictionaries({}, optional=fields)
