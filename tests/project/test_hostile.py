"""Hostile input at every edge: each input parses, or gives the project's own located error.

Covered edges: wire messages (dicts, JSON text, bytes), the dynamic_event
description, machine inputs, JSON records, the driver, vector files, state
and fleet snapshots.  The inputs include deep nesting, 10 MB strings,
1,000-digit integers, NaN and infinities, duplicate keys, invalid UTF-8 and
goal UUIDs of the wrong length.  The documented limits (a description of
1,000,000 bytes, a log text of 16,384 characters) are refused above the limit
with a clear sentence, and parsing stays within a small multiple of the input
in memory.
"""

from __future__ import annotations

import contextlib
import json
import tracemalloc
from collections.abc import Callable
from typing import Any

import attrs
import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent import descriptions
from dynevent.conformance.records import InvalidRecord, config_from_json, input_from_json, output_from_json
from dynevent.conformance.vectors import InvalidVector, parse_vector_file
from dynevent.conformance.vectors.driver import Driver
from dynevent.errors import (
    DyneventError,
    InvalidDescription,
    InvalidMessage,
    InvalidSnapshot,
    UnknownCategory,
    short_repr,
)
from dynevent.server import inputs as ins
from dynevent.server import machine, snapshot
from dynevent.server.fleet import Fleet
from dynevent.testing.strategies import hostile_json_values
from dynevent.wire.description import MAX_DESCRIPTION_BYTES, EventDescription
from dynevent.wire.messages import MESSAGE_TYPES, Goal
from dynevent.wire.vocab import EventType, RejectReason

TEN_MB = "x" * 10_000_000
DEEP = "[" * 100_000 + "]" * 100_000
HUGE_INT = "9" * 1_000
BAD_UTF8 = b'{"id": "\xff\xfe"}'
DUPLICATE_KEYS = '{"id": 1, "id": 2}'

HOSTILE_TEXTS: list[str | bytes] = [
    DEEP,
    '{"a":' * 5_000 + "1" + "}" * 5_000,
    f'{{"id": {HUGE_INT}}}',
    f'{{"id": -{HUGE_INT}}}',
    DUPLICATE_KEYS,
    BAD_UTF8,
    b"\xc0\x80",
    '{"stubborn_period": NaN}',
    '{"stubborn_period": Infinity}',
    '{"stubborn_period": 1e400}',
    '{"category": "\\ud800"}',
    '{"category": "\\u0000"}',
    "",
    "nul\x00l",
    "[]",
    "null",
    '"just a string"',
    json.dumps({"id": True}),
    json.dumps({"logs": [{"seq": 1.5}]}),
    json.dumps({"time": {"sec": 2**31}}),
]


def _edge_errors(function: Callable[[Any], object], value: Any, allowed: type[DyneventError]) -> None:
    try:
        function(value)
    except allowed as exc:
        assert str(exc)  # located and readable
    except DyneventError as exc:  # pragma: no cover - a wrong error type is a failure
        pytest.fail(f"{type(exc).__name__} instead of {allowed.__name__}: {exc}")


@pytest.mark.parametrize("cls", MESSAGE_TYPES, ids=lambda cls: cls.__name__)
@pytest.mark.parametrize("text", HOSTILE_TEXTS, ids=range(len(HOSTILE_TEXTS)))
def test_wire_messages_refuse_hostile_text(cls: Any, text: str | bytes) -> None:
    _edge_errors(cls.from_json, text, InvalidMessage)


def test_ten_megabyte_string_fields_are_carried_or_refused_by_limit() -> None:
    goal = Goal.from_json(json.dumps({"event_type": 1, "description": TEN_MB}))
    assert len(goal.description) == 10_000_000
    config = machine.ServerConfig(categories={"go_to_place": machine.any_description})
    state = machine.step(
        machine.State.new("tinyRobot", "r1"), ins.Begin(description="{}", event_id=1, now=0), config
    ).state
    request = Goal(
        dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place", description=TEN_MB, id=2
    )
    decision = machine.accept(state, request, config)
    assert decision.reason is RejectReason.DESCRIPTION_INVALID  # type: ignore[union-attr]
    assert "above the limit of 1000000" in decision.text  # type: ignore[union-attr]


@pytest.mark.parametrize("text", HOSTILE_TEXTS, ids=range(len(HOSTILE_TEXTS)))
def test_description_refuses_hostile_text(text: str | bytes) -> None:
    _edge_errors(EventDescription.from_json, text, InvalidDescription)


def test_description_size_limit() -> None:
    padding = "x" * (MAX_DESCRIPTION_BYTES - len('{"detail":""}'))
    assert EventDescription.from_json(f'{{"detail":"{padding}"}}').detail == padding
    with pytest.raises(InvalidDescription, match="above the limit of 1000000"):
        EventDescription.from_json(f'{{"detail":"{padding}x"}}')
    with pytest.raises(InvalidDescription):
        EventDescription.from_json(f'{{"detail":"{TEN_MB}"}}')


def test_log_text_limit() -> None:
    ins.ChildProgress(status="underway", log_text="x" * ins.MAX_LOG_TEXT_LENGTH, now=0)
    with pytest.raises(InvalidMessage, match="above the limit of 16384"):
        ins.ChildProgress(status="underway", log_text="x" * (ins.MAX_LOG_TEXT_LENGTH + 1), now=0)
    with pytest.raises(InvalidMessage):
        ins.ChildProgress(status="underway", log_text=TEN_MB, now=0)


@pytest.mark.parametrize(
    "uuid",
    [
        *(b"\x00" * 15, b"\x00" * 17, "0" * 31, "0" * 33, "g" * 32, "", 7, None, b"", bytearray(3)),
        # int(text, 16) and uuid.UUID take these; a goal UUID is hex digits only
        *("0000_" + "0" * 27, " " + "0" * 31, "+" + "0" * 31, "0x" + "0" * 30, "{" + "0" * 32 + "}"),
        "00000000-0000-0000-0000-00000000000_",
    ],
)
def test_goal_uuid_of_the_wrong_shape_is_refused(uuid: Any) -> None:
    with pytest.raises(InvalidMessage, match=r"GoalStarted\.goal_uuid"):
        ins.GoalStarted(goal_uuid=uuid, now=0)


@pytest.mark.parametrize(
    "uuid", ["AbCdEf0123456789" * 2, "abcdef01-2345-6789-ABCD-ef0123456789", bytes(range(16))]
)
def test_goal_uuid_is_stored_as_32_lowercase_hex_digits(uuid: Any) -> None:
    class Text(str):
        pass

    assert ins.GoalStarted(goal_uuid=Text("ab" * 16), now=0).goal_uuid == "ab" * 16
    stored = ins.GoalStarted(goal_uuid=uuid, now=0).goal_uuid
    assert len(stored) == 32 and set(stored) <= set("0123456789abcdef")
    assert int(stored, 16) == int(uuid.hex() if isinstance(uuid, bytes) else uuid.replace("-", ""), 16)


@pytest.mark.parametrize("now", [2**31 * 10**9, -(2**31) * 10**9 - 1, 1.5, True, int(HUGE_INT), None])
def test_times_outside_builtin_time_are_refused(now: Any) -> None:
    with pytest.raises(InvalidMessage, match=r"Tick\.now"):
        ins.Tick(now=now)


@given(value=hostile_json_values())
def test_records_accept_or_refuse_arbitrary_json(value: Any) -> None:
    for parse in (input_from_json, output_from_json, config_from_json):
        try:
            parse(value)
        except InvalidRecord as exc:
            assert exc.path.startswith("$")


@pytest.mark.parametrize("text", HOSTILE_TEXTS, ids=range(len(HOSTILE_TEXTS)))
def test_snapshots_refuse_hostile_text(text: str | bytes) -> None:
    _edge_errors(snapshot.loads, text, InvalidSnapshot)
    _edge_errors(Fleet.loads, text, InvalidSnapshot)


@given(value=hostile_json_values())
def test_snapshot_restore_never_half_restores(value: Any) -> None:
    for document in (value, {"format": "dynevent.state", "version": 1, "state": value}):
        try:
            state = snapshot.restore(document)
        except InvalidSnapshot:
            continue
        assert snapshot.restore(snapshot.snapshot(state)) == state


@given(request=hostile_json_values())
def test_driver_answers_every_request(request: Any) -> None:
    answer = Driver().handle(request)
    assert answer["ok"] in (True, False)
    if not answer["ok"]:
        assert answer["error"]


@pytest.mark.parametrize("text", HOSTILE_TEXTS, ids=range(len(HOSTILE_TEXTS)))
def test_vector_files_refuse_hostile_text(text: str | bytes) -> None:
    with pytest.raises(InvalidVector) as caught:
        parse_vector_file("hostile.json", text)
    assert str(caught.value).startswith("hostile.json: $")


@given(value=hostile_json_values())
def test_vector_loader_accepts_or_locates_arbitrary_json(value: Any) -> None:
    for document in (value, {"vectors": [value]}, {"vectors": value}):
        try:
            parse_vector_file("fuzz.json", json.dumps(document))
        except InvalidVector as exc:
            assert exc.source == "fuzz.json" and exc.path.startswith("$")
        except ValueError as exc:  # json.dumps itself refuses lone surrogates when writing the fixture
            assert "surrogate" in str(exc) or "NaN" in str(exc)


@pytest.mark.parametrize(
    ("parse", "text"),
    [(Goal.from_json, json.dumps({"description": "y" * 2_000_000})), (EventDescription.from_json, DEEP)],
    ids=["2MB goal", "deep description"],
)
def test_parsing_memory_stays_bounded(parse: Callable[[str], object], text: str) -> None:
    tracemalloc.start()
    try:
        with contextlib.suppress(DyneventError):
            parse(text)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 10 * len(text) + 1_000_000


# --------------------------------------------------------------------------- what the fuzzer found


@pytest.mark.parametrize("status", [{"a": 1}, ["completed"], None, 3])
@pytest.mark.parametrize("cls", [ins.ChildProgress, ins.ChildFinished])
def test_a_child_status_of_the_wrong_json_type_is_refused_not_unhashable(cls: Any, status: Any) -> None:
    with pytest.raises(InvalidMessage) as caught:
        cls(status=status, now=0)
    assert caught.value.field == "status"


def test_a_store_whose_schema_text_is_not_utf8_is_refused(tmp_path: Any) -> None:
    """A store file the fuzzer corrupted: its schema's text is not UTF-8 (Python's sqlite3 raises
    UnicodeDecodeError reading it, not a DatabaseError)."""
    import shutil
    from pathlib import Path

    from dynevent.server.store import InvalidStore, StateStore

    path = tmp_path / "state.db"
    shutil.copy(Path(__file__).resolve().parents[1] / "data" / "store-non-utf8-schema.db", path)
    with pytest.raises(InvalidStore, match="is not a dynevent state store"):
        StateStore(path)


def test_a_trace_time_of_a_huge_integer_is_a_located_error() -> None:
    from dynevent.conformance.judge import TraceError, check_trace

    with pytest.raises(TraceError, match="time"):
        check_trace('{"type": "status", "time": ' + "9" * 400 + ', "message": {}}')


@pytest.mark.parametrize("status", ['{"a": 1}', '["succeeded"]'])
def test_a_result_record_status_of_the_wrong_json_type_is_a_located_error(status: str) -> None:
    from dynevent.conformance.judge import TraceError, check_trace

    line = (
        '{"type": "result", "time": 1, "goal_uuid": "'
        + "0" * 32
        + '", "status": '
        + status
        + ', "result": {}}'
    )
    with pytest.raises(TraceError, match="status"):
        check_trace(line)


_JSONISH = st.one_of(
    st.text(alphabet=' \t\n\r{}[]",:0123456789.eE+-truefalsnul\\x', max_size=40),
    st.recursive(
        st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=5),
        lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=3), inner, max_size=3),
        max_leaves=8,
    ).map(json.dumps),
)


@given(text=_JSONISH, padding=st.sampled_from(["", " ", "\n\t", "  x"]))
def test_the_strict_reader_decodes_as_the_standard_decoder_does(text: str, padding: str) -> None:
    """The reader calls the decoder's scanner directly: values and errors are the decoder's own."""
    from dynevent.wire import _json

    def outcome(decode: Any, source: str) -> tuple[str, Any]:
        try:
            return "value", decode(source)
        except (ValueError, _json.JsonProblem) as exc:
            return type(exc).__name__, str(exc)

    source = padding + text + padding
    standard = json.JSONDecoder(object_pairs_hook=_json._pairs).decode
    assert outcome(_json._decode, source) == outcome(standard, source)


def test_an_annotation_in_a_snapshot_is_an_unknown_field() -> None:
    """A queued goal's kept description check is never read from JSON: a snapshot cannot plant one."""
    from dynevent.errors import InvalidSnapshot
    from dynevent.server import snapshot
    from dynevent.server.machine import QueuedGoal, State
    from dynevent.wire.messages import Goal

    goal = Goal(dynamic_event_seq=1, event_type=1, category="go_to_place", description="{}", id=2)
    state = attrs.evolve(
        State.new("fleet", "robot"), seq=1, active=True, queued=(QueuedGoal(goal_uuid="a" * 32, goal=goal),)
    )
    data = json.loads(snapshot.dumps(state))
    assert "checked" not in data["state"]["queued"][0]
    data["state"]["queued"][0]["checked"] = []
    with pytest.raises(InvalidSnapshot, match=r"\$\.state\.queued\[0\]\.checked"):
        snapshot.restore(data)


# ------------------------------------------------------------------ the descriptions API, at any size

#: An integer of 5,001 digits: Python will not write it (more than 4,300 digits), as a message would.
LONG = 10**5_000
LONG_TEXT = "<an integer of about 5001 digits>"


@pytest.mark.parametrize("category", [{}, [], None, 0, LONG, b"clean", "patrol"], ids=short_repr)
def test_the_descriptions_api_refuses_what_is_not_a_category_with_its_own_error(category: Any) -> None:
    for call in (
        lambda: descriptions.read(category, 0),
        lambda: descriptions.shape_errors(category, 0),
        lambda: descriptions.conforms(category, 0),
        lambda: descriptions.schema(category),
        lambda: descriptions.shapes.form(category, 0),
    ):
        with pytest.raises(UnknownCategory, match=r"^no description schema for category "):
            call()
    assert descriptions.Robot().check(category, 0)[0].startswith("/: ")


@pytest.mark.parametrize(
    ("check", "line"),
    [
        (lambda: descriptions.shape_errors("clean", LONG), f"/: {LONG_TEXT} is not an object"),
        (lambda: descriptions.shape_errors("clean", {"zone": LONG}), f"/zone: {LONG_TEXT} is not a string"),
        (lambda: descriptions.shape_errors("sequence", [LONG]), f"/0: {LONG_TEXT} is not an object"),
        (  # not JSON (a tuple is no array), and still explained
            lambda: descriptions.shape_errors("sequence", ({"category": LONG, "description": (LONG,)},)),
            '/: [{"category": <an integer',
        ),
        (
            lambda: descriptions.shape_errors(
                "pickup", {"place": "a", "payload": {"sku": "b", "quantity": -LONG}}
            ),
            f"/payload/quantity: {LONG_TEXT} is less than 0",
        ),
        (lambda: descriptions.Robot().check("go_to_place", -LONG), f"/: {LONG_TEXT} is less than 0"),
        (
            lambda: descriptions.shape_validators()["sequence"](
                "sequence", [{"category": "clean", "description": LONG}]
            ),
            f"/0/description: {LONG_TEXT} is not an object",
        ),
    ],
)
def test_an_integer_too_long_to_write_is_named_by_its_length_in_an_explanation(
    check: Callable[[], tuple[str, ...]], line: str
) -> None:
    lines = check()
    assert lines[0].startswith(line), lines


@pytest.mark.parametrize(
    ("request_", "error"),
    [
        ({"op": LONG}, f"$.op: expected 'hello', 'reset' or 'apply', got {LONG_TEXT}"),
        (
            {"op": "reset", "fleet": "f", "robot": "r", "config": {"categories": {"x": {"accept": LONG}}}},
            f"$.config.categories.x.accept: expected one of ['any', 'string', 'number', 'array', 'object'], "
            f"got {LONG_TEXT}",
        ),
        (
            {"op": "reset", "fleet": "f", "robot": "r", "config": {"max_description_length": LONG}},
            f"$.config: ServerConfig.max_description_length: expected a positive integer of at most 1000000 "
            f"(bytes) (got {LONG_TEXT})",
        ),
    ],
    ids=["op", "accept", "max_description_length"],
)
def test_the_driver_names_an_integer_too_long_to_write_by_its_length(request_: Any, error: str) -> None:
    assert Driver().handle(request_) == {"ok": False, "error": error}
    driver = Driver()
    driver.handle({"op": "reset", "fleet": "f", "robot": "r"})
    answer = driver.handle({"op": "apply", "input": {"type": LONG}})
    assert answer["error"].endswith(f"got {LONG_TEXT}")
