"""The fast constructors: a value a field's fast check lets through is one its converter keeps.

:func:`dynevent.wire._fields.fast_init` skips a field's converter when the
field's fast check passes; that is sound only if every value the check passes
is one the converter returns unchanged (same type, same value).  Checked here
for every field of every class that has a fast check, on values around each
edge: range limits, non-ASCII and NUL text, enum members, bools posing as ints.
"""

from __future__ import annotations

import sys
from typing import Any

import attrs
import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.errors import InvalidMessage
from dynevent.server import inputs as ins
from dynevent.wire import messages
from dynevent.wire._fields import FAST_KEY, U32_MAX, U64_MAX, copier, fast_init
from dynevent.wire.vocab import EventType, Status, Tier

_CLASSES = [
    cls
    for module in (ins, messages)
    for cls in vars(module).values()
    if isinstance(cls, type) and attrs.has(cls) and cls.__module__ == module.__name__
]
_FIELDS = [(cls, field) for cls in _CLASSES for field in attrs.fields(cls) if FAST_KEY in field.metadata]

_EDGES = st.sampled_from(
    [0, 1, -1, 255, 256, U32_MAX, U32_MAX + 1, U64_MAX, U64_MAX + 1, -(2**63), 2**63, 2**31 * 10**9]
)
_VALUES = st.one_of(
    st.integers(),
    _EDGES,
    st.booleans(),
    st.none(),
    st.floats(),
    st.text(),
    st.text(alphabet="0123456789abcdefABCDEF-", min_size=30, max_size=37),
    st.sampled_from(["underway", "info", "a\x00b", "\ud800", "x" * 16_385, "x" * 16_384, "", "é"]),
    st.sampled_from([*Status, *Tier, *EventType]),
    st.just(()),
    st.tuples(st.integers()),
    st.builds(messages.Time, sec=st.integers(0, 10), nanosec=st.integers(0, 10)),
    st.builds(messages.Goal, id=st.integers(0, 10)),
)


def _passes(field: attrs.Attribute[Any], value: Any, cls: type) -> bool:
    namespace = dict(vars(sys.modules[cls.__module__]))
    namespace["v"] = value
    wire = field.metadata.get("dynevent.wire")
    if isinstance(wire, type):
        namespace[f"_{wire.__name__}"] = wire
    return bool(eval(field.metadata[FAST_KEY].format(v="v"), namespace))


def test_every_wire_and_input_class_has_the_fast_constructor() -> None:
    assert len(_CLASSES) >= 20
    for cls in _CLASSES:
        assert cls.__init__.__code__.co_filename == f"<fast init of {cls.__qualname__}>", cls


@pytest.mark.parametrize(("cls", "field"), _FIELDS, ids=lambda item: getattr(item, "name", str(item)))
@given(value=_VALUES)
def test_a_value_the_fast_check_passes_is_kept_by_the_converter(
    cls: type, field: attrs.Attribute[Any], value: Any
) -> None:
    if not _passes(field, value, cls):
        return
    converter = field.converter
    function = converter.converter  # type: ignore[union-attr]
    arguments = [value]
    if converter.takes_self:  # type: ignore[union-attr]
        arguments.append(object.__new__(cls))
    if converter.takes_field:  # type: ignore[union-attr]
        arguments.append(field)
    kept = function(*arguments)
    assert type(kept) is type(value) and (kept is value or kept == value)


@given(value=_VALUES)
def test_a_refused_value_gets_the_converter_s_own_error(value: Any) -> None:
    try:
        ins.ChildProgress(status=value, now=0)
    except InvalidMessage as exc:
        assert exc.field == "status" and "task_state statuses" in str(exc)
    else:
        assert value in {status.value for status in Status} or value in set(Status)


def test_defaults_and_factories_are_kept() -> None:
    assert ins.ChildProgress(status="underway", now=0).tier == "info"
    assert messages.Feedback().logs == ()
    first, second = messages.DynamicEventStatus(), messages.DynamicEventStatus()
    assert first.time == messages.Time() and first == second


def test_an_enum_member_is_stored_as_its_plain_value() -> None:
    progress = ins.ChildProgress(status=Status.UNDERWAY, tier=Tier.WARNING, now=0)
    assert type(progress.status) is str and type(progress.tier) is str
    goal = messages.Goal(event_type=EventType.CANCEL)
    assert type(goal.event_type) is int and goal.event_type == 2


def test_a_class_with_a_validator_is_refused() -> None:
    @attrs.frozen(kw_only=True)
    class Checked:
        value: int = attrs.field(validator=attrs.validators.instance_of(int))

    with pytest.raises(TypeError, match=r"Checked\.value"):
        fast_init(Checked)


def test_an_empty_sequence_must_be_a_plain_tuple_to_skip_its_converter() -> None:
    class Empty(tuple):  # type: ignore[type-arg]
        pass

    assert type(messages.Feedback(logs=Empty()).logs) is tuple
    with pytest.raises(InvalidMessage, match=r"Feedback\.logs"):
        messages.Feedback(logs=_EqualsEverything())


class _EqualsEverything:
    def __eq__(self, other: object) -> bool:
        return True

    __hash__ = None  # type: ignore[assignment]


def test_a_copier_takes_the_changed_fields_in_order_and_keeps_the_rest() -> None:
    time = messages.Time(sec=1, nanosec=2)
    status = messages.DynamicEventStatus(dynamic_event_seq=3, status="standby", id=4, time=time)
    copy = copier(messages.DynamicEventStatus, "status", "id")
    copied = copy(status, "underway", 5)
    assert copied == attrs.evolve(status, status="underway", id=5)
    assert copied.time is time and status.status == "standby"
    with pytest.raises(TypeError, match="no fields"):
        copier(messages.DynamicEventStatus, "colour")
