"""The fleet: robots keyed by (fleet, robot), routing by key and by name, whole-fleet snapshots."""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.errors import DyneventError, InvalidName, InvalidSnapshot
from dynevent.server import inputs as ins
from dynevent.server import machine, snapshot
from dynevent.server.fleet import FORMAT, VERSION, DuplicateRobot, Fleet, RobotKey, Routed, UnknownRobot
from dynevent.server.machine import ServerConfig, State, any_description
from dynevent.server.outputs import Accepted, GoalAccepted, GoalRejected, Rejected, StartChild
from dynevent.wire.messages import Goal
from dynevent.wire.names import BEGIN_TOPIC, NameKind, build_name, parse_name
from dynevent.wire.vocab import EventType, RejectReason

DOC = Path(__file__).resolve().parents[2] / "docs" / "fleet.md"
DOC_BLOCKS = re.findall(r"```python\n(.*?)```", DOC.read_text(encoding="utf-8"), flags=re.DOTALL)

SECOND = 1_000_000_000
UUIDS = tuple(f"{index:032x}" for index in range(1, 5))


def _needs_place(category: str, description: Any) -> Sequence[str]:
    return () if isinstance(description, dict) and "place" in description else ("no place",)


GO = ServerConfig(categories={"go_to_place": any_description})
ACT = ServerConfig(categories={"perform_action": any_description}, stubborn_minimum=3.0)
STRICT = ServerConfig.rmf_ros2({"go_to_place": _needs_place, "perform_action": any_description})


def _begin(now: int = 0, event_id: int = 10) -> ins.Begin:
    return ins.Begin(description='{"category": "patrol"}', event_id=event_id, now=now)


def _next(seq: int = 1, child: int = 11, category: str = "go_to_place") -> Goal:
    return Goal(
        dynamic_event_seq=seq,
        event_type=EventType.NEXT,
        category=category,
        description='{"place": "pantry"}',
        id=child,
    )


def _fleet() -> Fleet:
    fleet = Fleet(GO, fleet_configs={"beta": STRICT})
    fleet.add("alpha", "r1")
    fleet.add("alpha", "r2", ACT)
    fleet.add("beta", "r1")
    return fleet


# --------------------------------------------------------------------------- robots


def test_add_remove_and_dict_like_views() -> None:
    fleet = _fleet()
    assert len(fleet) == 3
    assert list(fleet) == [("alpha", "r1"), ("alpha", "r2"), ("beta", "r1")]
    assert all(type(key) is RobotKey for key in fleet)
    assert ("alpha", "r2") in fleet
    assert RobotKey("beta", "r1") in fleet
    assert ("beta", "r2") not in fleet
    assert ["not", "hashable"] not in fleet
    assert dict(fleet.items())[RobotKey("alpha", "r1")] == State.new("alpha", "r1")
    fleet.step("alpha", "r2", _begin())
    last = fleet.remove("alpha", "r2")
    assert last.active and last.seq == 1
    assert list(fleet) == [("alpha", "r1"), ("beta", "r1")]
    assert fleet.add("alpha", "r2") == ("alpha", "r2")  # back, fresh
    assert fleet.state("alpha", "r2") == State.new("alpha", "r2")
    assert repr(fleet) == "<Fleet of 3 robots>"


def test_add_with_a_state() -> None:
    fleet = Fleet()
    state = machine.step(State.new("alpha", "r1"), _begin(), GO).state
    fleet.add("alpha", "r1", GO, state=state)
    assert fleet.state("alpha", "r1") is state
    with pytest.raises(ValueError, match="another robot"):
        fleet.add("alpha", "r2", state=state)


def test_duplicate_add_is_refused_and_keeps_the_robot() -> None:
    fleet = _fleet()
    fleet.step("alpha", "r1", _begin())
    with pytest.raises(DuplicateRobot, match="'r1' of fleet 'alpha' is already") as caught:
        fleet.add("alpha", "r1")
    assert isinstance(caught.value, DyneventError)
    assert fleet.state("alpha", "r1").active


@pytest.mark.parametrize(
    ("fleet_name", "robot", "field"),
    [
        ("", "r1", "fleet"),
        ("alpha", "r 1", "robot"),
        ("1alpha", "r1", "fleet"),
        ("alpha", "r__1", "robot"),
        ("alpha", "r/1", "robot"),
        ("alpha", "r" * 240, "robot"),  # the action's derived names would be too long
        (None, "r1", "fleet"),
    ],
)
def test_bad_names_are_refused(fleet_name: Any, robot: Any, field: str) -> None:
    fleet = Fleet()
    with pytest.raises(InvalidName) as caught:
        fleet.add(fleet_name, robot)
    assert caught.value.field == field
    assert len(fleet) == 0


def test_unknown_robot_is_a_key_error_and_a_dynevent_error() -> None:
    fleet = _fleet()
    for call in (
        lambda: fleet.step("alpha", "r9", _begin()),
        lambda: fleet.state("gamma", "r1"),
        lambda: fleet.config("alpha", "r9"),
        lambda: fleet.remove("alpha", "r9"),
        lambda: fleet.accept("alpha", "r9", _next()),
        lambda: fleet.status_message("alpha", "r9", 0),
        lambda: fleet.set_config("alpha", "r9", GO),
    ):
        with pytest.raises(UnknownRobot) as caught:
            call()
        error = caught.value
        assert isinstance(error, KeyError)
        assert isinstance(error, ValueError)
        assert isinstance(error, DyneventError)
        assert "is not in this fleet" in str(error)
        assert not str(error).startswith('"')  # not KeyError's repr
    assert len(fleet) == 3


def test_a_malformed_key_is_an_invalid_name_not_an_unknown_robot() -> None:
    fleet = _fleet()
    with pytest.raises(InvalidName):
        fleet.step("alpha", "r 1", _begin())
    with pytest.raises(InvalidName):
        fleet.state(["alpha"], "r1")  # type: ignore[arg-type]


# --------------------------------------------------------------------------- configs


def test_config_is_the_robot_s_own_else_its_fleet_s_else_the_default() -> None:
    fleet = _fleet()
    assert fleet.config("alpha", "r1") is GO
    assert fleet.config("alpha", "r2") is ACT
    assert fleet.config("beta", "r1") is STRICT
    assert fleet.default_config("beta") is STRICT
    assert fleet.default_config("gamma") is GO
    fleet.set_fleet_config("gamma", ACT)
    fleet.add("gamma", "r1")
    assert fleet.config("gamma", "r1") is ACT
    fleet.set_fleet_config("gamma", None)
    fleet.add("gamma", "r2")
    assert fleet.config("gamma", "r2") is GO
    assert fleet.config("gamma", "r1") is ACT  # chosen when added
    fleet.set_config("gamma", "r1", STRICT)
    assert fleet.config("gamma", "r1") is STRICT
    assert isinstance(Fleet().default_config("x"), ServerConfig)


def test_configs_must_be_server_configs() -> None:
    with pytest.raises(TypeError):
        Fleet("config")  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        Fleet(fleet_configs={"alpha": 1})  # type: ignore[dict-item]
    with pytest.raises(InvalidName):
        Fleet(fleet_configs={"al pha": GO})
    with pytest.raises(TypeError):
        Fleet().add("alpha", "r1", {"go_to_place": any_description})  # type: ignore[arg-type]


def test_each_robot_decides_with_its_own_config() -> None:
    fleet = _fleet()
    for key in fleet:
        fleet.step(*key, _begin())
    assert isinstance(fleet.accept("alpha", "r1", _next()), Accepted)
    rejected = fleet.accept("alpha", "r2", _next())
    assert isinstance(rejected, Rejected)
    assert rejected.reason is RejectReason.UNSUPPORTED_CATEGORY
    assert isinstance(fleet.accept("alpha", "r2", _next(category="perform_action")), Accepted)
    # beta validates go_to_place descriptions and assigns ids itself (rmf_ros2 options)
    bad = Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place", description="{}")
    decision = fleet.accept("beta", "r1", bad)
    assert isinstance(decision, Rejected) and decision.reason is RejectReason.DESCRIPTION_INVALID
    assert isinstance(fleet.accept("beta", "r1", _next(child=0)), Accepted)


def test_stepping_one_robot_leaves_the_others_alone() -> None:
    fleet = _fleet()
    before = dict(fleet.items())
    outputs = fleet.step("alpha", "r2", _begin())
    expected = machine.step(State.new("alpha", "r2"), _begin(), ACT)
    assert outputs == expected.outputs
    assert fleet.state("alpha", "r2") == expected.state
    assert fleet.state("alpha", "r1") is before[RobotKey("alpha", "r1")]
    assert fleet.state("beta", "r1") is before[RobotKey("beta", "r1")]
    assert fleet.status_message("alpha", "r2", 5) == machine.status_message(expected.state, 5)


# --------------------------------------------------------------------------- routing by name


@pytest.mark.parametrize("kind", list(NameKind))
@pytest.mark.parametrize("slash", ["", "/"])
def test_every_per_robot_name_routes_to_its_robot(kind: NameKind, slash: str) -> None:
    fleet = _fleet()
    for key in list(fleet):
        name = slash + build_name(kind, *key)
        assert fleet.route(name) == key
        routed = fleet.step_by_name(name, ins.DescriptionQuery(now=0))
        assert isinstance(routed, Routed)
        assert routed.key == key and type(routed.key) is RobotKey
        assert len(routed.outputs) == 1


def test_step_by_name_returns_the_robot_and_its_outputs() -> None:
    fleet = _fleet()
    fleet.step("alpha", "r1", _begin())
    request = ins.GoalRequested(goal_uuid=UUIDS[0], goal=_next(), now=1)
    key, outputs = fleet.step_by_name("rmf/dynamic_event/command/alpha/r1", request)
    assert key == ("alpha", "r1")
    assert outputs == (GoalAccepted(goal_uuid=UUIDS[0]),)
    # the same goal on alpha/r2's action: that robot has no active dynamic event
    key, outputs = fleet.step_by_name("rmf/dynamic_event/command/alpha/r2", request)
    assert key == ("alpha", "r2")
    assert isinstance(outputs[0], GoalRejected)
    assert outputs[0].rejection.reason is RejectReason.SEQ_MISMATCH


@pytest.mark.parametrize(
    "name",
    [
        BEGIN_TOPIC,
        "/" + BEGIN_TOPIC,
        "rmf/dynamic_event/command/alpha",
        "rmf/dynamic_event/command/alpha/r1/extra",
        "rmf/dynamic_event/commands/alpha/r1",
        "//rmf/dynamic_event/command/alpha/r1",
        "rmf/dynamic_event/command/alpha/r 1",
        "rmf/dynamic_event/command//r1",
        "",
        "/",
        "alpha/r1",
        b"rmf/dynamic_event/command/alpha/r1",
        None,
    ],
)
def test_names_that_are_not_per_robot_names_are_refused(name: Any) -> None:
    fleet = _fleet()
    with pytest.raises(InvalidName):
        fleet.route(name)
    with pytest.raises(InvalidName):
        fleet.step_by_name(name, ins.DescriptionQuery(now=0))


def test_a_well_formed_name_of_an_absent_robot_is_unknown() -> None:
    fleet = _fleet()
    with pytest.raises(UnknownRobot):
        fleet.route("rmf/dynamic_event/status/beta/r2")
    with pytest.raises(UnknownRobot):
        fleet.step_by_name("/rmf_dynamic_event/description/gamma/r1", ins.DescriptionQuery(now=0))


_TOKENS = st.from_regex(r"[A-Za-z][A-Za-z0-9]{0,6}(_[A-Za-z0-9]{1,3}){0,2}", fullmatch=True)


@given(
    robots=st.lists(st.tuples(_TOKENS, _TOKENS), min_size=1, max_size=8, unique=True),
    probe=st.tuples(_TOKENS, _TOKENS),
    kind=st.sampled_from(list(NameKind)),
    slash=st.booleans(),
)
def test_routing_agrees_with_parse_name(
    robots: list[tuple[str, str]], probe: tuple[str, str], kind: NameKind, slash: bool
) -> None:
    fleet = Fleet()
    for key in robots:
        fleet.add(*key)
    for key in [*robots, probe]:
        name = ("/" if slash else "") + build_name(kind, *key)
        parsed = parse_name(name)
        if key in robots:
            assert fleet.route(name) == (parsed.fleet, parsed.robot) == key
        else:
            with pytest.raises(UnknownRobot):
                fleet.route(name)


@given(name=st.text(alphabet="rmf_dynamicevntsaubgplo/12", max_size=50))
def test_routing_any_text_gives_a_key_or_the_project_s_errors(name: str) -> None:
    fleet = Fleet()
    fleet.add("f1", "r1")
    try:
        key = fleet.route(name)
    except (InvalidName, UnknownRobot):
        return
    assert key == ("f1", "r1")
    assert parse_name(name)[1:] == key


# --------------------------------------------------------------------------- snapshots

ROBOTS = (RobotKey("alpha", "r1"), RobotKey("alpha", "r2"), RobotKey("beta", "r1"))
_CONFIGS = {ROBOTS[0]: GO, ROBOTS[1]: ACT, ROBOTS[2]: STRICT}
_STATUSES = ("underway", "delayed", "blocked", "completed", "failed", "canceled", "killed", "skipped")
_DESCRIPTIONS = ('{"place": "pantry"}', "{}", "not json", '"lobby"')
_KINDS = (
    "begin",
    "request",
    "request",
    "request",
    "start",
    "start",
    "cancel",
    "progress",
    "progress",
    "finish",
    "tick",
    "interrupt",
    "resume",
    "task_cancel",
    "task_kill",
    "query",
    "shutdown",
)

#: One scripted step: (robot index, kind, two small choices).
Script = tuple[int, str, int, int]
scripts = st.lists(
    st.tuples(
        st.integers(0, len(ROBOTS) - 1),
        st.sampled_from(_KINDS),
        st.integers(0, 7),
        st.integers(0, 7),
    ),
    max_size=60,
)


def _input(state: State, index: int, kind: str, a: int, b: int) -> ins.Input:
    """The input a scripted step stands for; goals mostly fit the state so that runs go somewhere."""
    now = index * SECOND // 3
    if (kind in ("task_cancel", "task_kill") and a < 5) or (kind == "shutdown" and (a, b) != (7, 7)):
        kind = "progress"  # rare: they end a run (or the robot) for good
    if not state.active and not state.shutdown and a < 6:
        kind = "begin"  # an inactive robot mostly begins, so that runs go somewhere
    if kind == "begin":
        return ins.Begin(description='{"category": "patrol"}', event_id=100 * a, now=now)
    if kind == "request":
        running = state.running
        event_type = (EventType.NEXT, EventType.NEXT, EventType.CANCEL, EventType.FINISHED, 0, 7)[a % 6]
        child = running.child_id if running is not None and b % 3 else state.last_id + 1 + b % 2
        goal = Goal(
            dynamic_event_seq=state.seq if b != 7 else state.seq + 1,
            event_type=event_type,
            category=("go_to_place", "perform_action", "dance")[b % 3 if b > 4 else a % 2],
            description=_DESCRIPTIONS[(a + b) % 4 if b > 5 else 0],
            id=child,
            stubborn_period=(0.0, 0.5, 4.0, math.nan)[b % 4 if b > 3 else 0],
        )
        return ins.GoalRequested(goal_uuid=UUIDS[b % 4], goal=goal, now=now)
    if kind == "start":
        queued = state.queued
        uuid = queued[a % len(queued)].goal_uuid if queued and b else UUIDS[a % 4]
        return ins.GoalStarted(goal_uuid=uuid, now=now)
    if kind == "cancel":
        uuid = state.running.goal_uuid if state.running is not None and a % 2 else UUIDS[b % 4]
        return ins.CancelRequested(goal_uuid=uuid, now=now)
    if kind == "progress":
        text = None if b % 2 else f"step {index}"
        return ins.ChildProgress(
            status=_STATUSES[a % 3], log_text=text, tier=("info", "warning")[b % 2], now=now
        )
    if kind == "finish":
        return ins.ChildFinished(status=_STATUSES[3 + a % 5], now=now)
    if kind == "tick":
        return ins.Tick(now=now, map_name=("L1", "L2")[b % 2], x=float(a) / 20, y=0.0)
    simple: dict[str, type[ins.Input]] = {
        "interrupt": ins.Interrupt,
        "resume": ins.Resume,
        "task_cancel": ins.TaskCancel,
        "task_kill": ins.TaskKill,
        "query": ins.DescriptionQuery,
        "shutdown": ins.Shutdown,
    }
    return simple[kind](now=now)  # type: ignore[call-arg]


def _play(fleet: Fleet, script: Sequence[Script], offset: int = 0) -> list[tuple[Any, ...]]:
    outputs: list[tuple[Any, ...]] = []
    for index, (robot, kind, a, b) in enumerate(script, start=offset):
        key = ROBOTS[robot]
        outputs.append(fleet.step(*key, _input(fleet.state(*key), index, kind, a, b)))
    return outputs


def _scripted_fleet() -> Fleet:
    fleet = Fleet()
    for key in ROBOTS:
        fleet.add(*key, _CONFIGS[key])
    return fleet


def _lookup(fleet_name: str, robot: str) -> ServerConfig:
    return _CONFIGS[RobotKey(fleet_name, robot)]


@given(script=scripts, cut=st.integers(0, 60))
def test_snapshot_round_trip_gives_equal_states_and_identical_continuations(
    script: list[Script], cut: int
) -> None:
    cut = min(cut, len(script))
    fleet = _scripted_fleet()
    _play(fleet, script[:cut])
    text = fleet.dumps()
    restored = Fleet.loads(text, _lookup)
    assert list(restored) == list(fleet)
    assert dict(restored.items()) == dict(fleet.items())
    assert all(restored.config(*key) is _CONFIGS[key] for key in ROBOTS)
    assert restored.dumps() == text
    assert _play(restored, script[cut:], cut) == _play(fleet, script[cut:], cut)
    assert dict(restored.items()) == dict(fleet.items())


def test_the_scripted_runs_reach_the_interesting_states() -> None:
    """The generator of the round-trip test is not a toy: a fixed script runs a child to its end."""
    fleet = _scripted_fleet()
    script: list[Script] = [
        (0, "begin", 1, 0),
        (0, "request", 0, 0),
        (0, "start", 0, 1),
        (0, "progress", 0, 0),
    ]
    outputs = _play(fleet, script)
    assert any(isinstance(output, StartChild) for output in outputs[2])
    assert fleet.state(*ROBOTS[0]).running is not None
    text = fleet.dumps()
    assert Fleet.loads(text, _lookup).state(*ROBOTS[0]) == fleet.state(*ROBOTS[0])


def test_the_snapshot_document_is_one_json_object_of_robot_snapshots() -> None:
    fleet = _fleet()
    fleet.step("alpha", "r1", _begin())
    document = json.loads(fleet.dumps())
    assert document["format"] == FORMAT == "dynevent.server.fleet"
    assert document["version"] == VERSION == 1
    assert document["robots"] == [snapshot.snapshot(state) for _, state in fleet.items()]
    assert fleet.snapshot() == document
    assert Fleet.restore(document).state("alpha", "r1") == fleet.state("alpha", "r1")
    assert len(Fleet.loads(Fleet().dumps())) == 0


def test_restore_takes_configs_from_the_lookup_else_the_defaults() -> None:
    fleet = _fleet()
    asked: list[tuple[str, str]] = []

    def lookup(fleet_name: str, robot: str) -> ServerConfig | None:
        asked.append((fleet_name, robot))
        return ACT if robot == "r2" else None

    restored = Fleet.restore(fleet.snapshot(), lookup, config=GO, fleet_configs={"beta": STRICT})
    assert asked == list(fleet)
    assert restored.config("alpha", "r1") is GO
    assert restored.config("alpha", "r2") is ACT
    assert restored.config("beta", "r1") is STRICT
    plain = Fleet.restore(fleet.snapshot())
    assert plain.config("alpha", "r2") is plain.config("beta", "r1")


def _document() -> dict[str, Any]:
    fleet = _fleet()
    fleet.step("alpha", "r2", _begin())
    return fleet.snapshot()


def _set(document: dict[str, Any], path: Sequence[Any], value: Any) -> dict[str, Any]:
    target: Any = document
    for step in path[:-1]:
        target = target[step]
    if value is _DELETE:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return document


_DELETE = object()


@pytest.mark.parametrize(
    ("path", "value", "where"),
    [
        (("format",), "dynevent.state", "$.format"),
        (("format",), _DELETE, "$.format"),
        (("version",), 2, "$.version"),
        (("version",), 0, "$.version"),
        (("version",), True, "$.version"),
        (("version",), 1.0, "$.version"),
        (("version",), "1", "$.version"),
        (("version",), _DELETE, "$.version"),
        (("robots",), {}, "$.robots"),
        (("robots",), _DELETE, "$.robots"),
        (("extra",), [], "$"),
        (("robots", 1), [], "$.robots[1]"),
        (("robots", 1, "version"), 9, "$.robots[1].version"),
        (("robots", 1, "format"), "dynevent.server.fleet", "$.robots[1].format"),
        (("robots", 1, "state", "seq"), -1, "$.robots[1].state.seq"),
        (("robots", 1, "state", "status"), "lost", "$.robots[1].state.status"),
        (("robots", 2, "state", "robot"), "r 1", "$.robots[2].state.robot"),
        (("robots", 0, "state", "robot"), "r2", "$.robots[1]"),  # alpha/r2 twice: the second
        (("robots", 0, "state", "robot"), "r" * 240, "$.robots[0].state"),  # too long a name
        (("robots", 2, "state", "mood"), "happy", "$.robots[2].state.mood"),
    ],
)
def test_corrupt_documents_are_refused_with_a_path(path: Sequence[Any], value: Any, where: str) -> None:
    document = _set(_document(), path, value)
    with pytest.raises(InvalidSnapshot) as caught:
        Fleet.restore(document)
    assert caught.value.path == where
    with pytest.raises(InvalidSnapshot):
        Fleet.loads(json.dumps(document))


@pytest.mark.parametrize(
    "document",
    [
        None,
        [],
        "dynevent.server.fleet",
        1,
        {"format": "dynevent.server.fleet"},
        snapshot.snapshot(State.new("a", "b")),
    ],
)
def test_what_is_not_a_fleet_snapshot_is_refused(document: Any) -> None:
    with pytest.raises(InvalidSnapshot):
        Fleet.restore(document)


@pytest.mark.parametrize(
    "text",
    ["", "{", '{"format": "dynevent.server.fleet", "format": "x"}', b"\xff\xfe", "[" * 100 + "]" * 100],
)
def test_text_that_is_not_json_is_refused(text: str | bytes) -> None:
    with pytest.raises(InvalidSnapshot) as caught:
        Fleet.loads(text)
    assert caught.value.path == "$"


def test_a_failing_restore_leaves_no_fleet_and_the_original_intact() -> None:
    fleet = _fleet()
    fleet.step("alpha", "r2", _begin())
    before = fleet.dumps()
    document = fleet.snapshot()
    document["robots"][2]["state"]["seq"] = 2**32
    result: Fleet | None = None
    with pytest.raises(InvalidSnapshot):
        result = Fleet.restore(document)
    assert result is None
    assert fleet.dumps() == before


def _mutations() -> st.SearchStrategy[tuple[list[int], Any]]:
    return st.tuples(
        st.lists(st.integers(0, 30), min_size=1, max_size=5),
        st.one_of(st.none(), st.integers(-2, 2**65), st.text(max_size=5), st.booleans(), st.just([])),
    )


@given(mutation=_mutations())
def test_a_mutated_document_restores_or_is_refused_never_anything_else(
    mutation: tuple[list[int], Any],
) -> None:
    choices, value = mutation
    document = _document()
    parent: Any = None
    key: Any = None
    target: Any = document
    for choice in choices:  # walk down the document, then replace what we reached
        keys = list(target) if isinstance(target, dict) else list(range(len(target)))
        if not keys:
            break
        parent, key = target, keys[choice % len(keys)]
        target = parent[key]
        if not isinstance(target, (dict, list)) or choice % 7 == 0:
            break
    if parent is None:
        return
    parent[key] = value
    try:
        restored = Fleet.restore(document)
    except InvalidSnapshot:
        return
    assert Fleet.loads(restored.dumps()).snapshot() == restored.snapshot()


# --------------------------------------------------------------------------- docs/fleet.md


def test_the_fleet_doc_has_examples() -> None:
    assert DOC_BLOCKS


@pytest.mark.parametrize("index", range(len(DOC_BLOCKS)))
def test_the_fleet_doc_example_runs(index: int, capsys: pytest.CaptureFixture[str]) -> None:
    exec(compile(DOC_BLOCKS[index], f"docs/fleet.md example {index + 1}", "exec"), {})
    out = capsys.readouterr().out
    for expected in re.findall(r"print\(.*?\)\s*# (.+)", DOC_BLOCKS[index]):
        assert expected in out
