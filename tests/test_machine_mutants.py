"""Tests that kill the mutants mutmut made of src/dynevent/server/machine.py (see docs/testing.md).

Each test pins a behaviour the scenario tests left loose: the configuration's
validation errors, keyword-only construction, the initial state, the exact
human sentences of rejections and ``Ignored`` notices, the uint64 wrap of
adapter ids, the integer log time, and the transition table behind the
diagram of docs/spec.md.  The sentences are free for the spec (scenario.py
compares them to ``ANY_TEXT``) but users read them in logs and CLI output,
so a change to one must be deliberate.
"""

from __future__ import annotations

import math
import re
import typing
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import attrs
import pytest

from dynevent.errors import InvalidConfig, InvalidName
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import (
    Position,
    QueuedGoal,
    RunningGoal,
    ServerConfig,
    State,
    Stubbornness,
    Transition,
    accept_any,
    allowed_targets,
)
from dynevent.tools.diagram import render
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import DynamicState, EventType, IdPolicy, RejectReason
from scenario import (
    CONFIG,
    FLEET,
    PARSE_FAILURE,
    ROBOT,
    T0,
    Run,
    aborted,
    cancel_goal,
    deferred,
    entry,
    finished_goal,
    goal,
    next_goal,
    running,
    start_child,
    u,
    waiting,
)

R = RejectReason
U64_MAX = 2**64 - 1
SPEC = (Path(__file__).resolve().parents[1] / "docs" / "spec.md").read_text(encoding="utf-8")
ADAPTER = attrs.evolve(CONFIG, id_policy=IdPolicy.ADAPTER)


def _rejection(outputs: tuple[Any, ...]) -> outs.Rejected:
    assert len(outputs) == 1
    assert isinstance(outputs[0], outs.GoalRejected)
    return outputs[0].rejection


# --------------------------------------------------------------------------- ServerConfig validation


@pytest.mark.parametrize("value", [["go_to_place"], "go_to_place", None, 3])
def test_categories_must_be_a_mapping(value: Any) -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(categories=value)
    assert isinstance(caught.value, TypeError)
    assert str(caught.value) == (
        f"ServerConfig.categories: expected a mapping of category to validator (got {value!r})"
    )


@pytest.mark.parametrize(
    ("categories", "key"),
    [
        ({1: accept_any}, 1),  # a callable validator under a non-str name
        ({"dock": "not callable"}, "dock"),  # a str name mapped to a non-callable
        ({b"dock": None}, b"dock"),
    ],
    ids=["non-str-name", "non-callable", "neither"],
)
def test_each_category_maps_a_str_to_a_callable(categories: Mapping[Any, Any], key: object) -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(categories=categories)
    assert str(caught.value) == (
        f"ServerConfig.categories: each category must map a str to a callable (got {dict(categories)!r})"
    )
    assert caught.value.field == "categories"


def test_categories_are_copied() -> None:
    categories = {"dock": accept_any}
    config = ServerConfig(categories=categories)
    categories["other"] = accept_any
    assert set(config.categories) == {"dock"}


def _kwargs(field: str, value: Any) -> dict[str, Any]:
    return {field: value}


_BAD_NUMBERS = [0, 0.0, -1, -0.5, True, False, math.nan, math.inf, -math.inf, "2", None]


_BOUNDS = {
    "stubborn_minimum": "expected a number of seconds from 0.001 to 86400",
    "stubborn_refresh": "expected a number of seconds from 0.001 to 86400",
    "stubborn_move_threshold": "expected a number of metres from 0.01 to 1e+06",
}


@pytest.mark.spec("R0.1")
@pytest.mark.parametrize("field", sorted(_BOUNDS))
@pytest.mark.parametrize("value", [*_BAD_NUMBERS, 10**400, -(10**400), 1e300], ids=repr)
def test_stubborn_settings_must_be_numbers_the_machine_can_run(field: str, value: Any) -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(**_kwargs(field, value))
    assert isinstance(caught.value, ValueError)
    assert str(caught.value).startswith(f"ServerConfig.{field}: {_BOUNDS[field]} (got ")


@pytest.mark.spec("R0.1", "R19.7")
@pytest.mark.parametrize("refresh", [0.001, 86_400.0])
def test_the_extreme_refresh_periods_run(refresh: float) -> None:
    config = ServerConfig(
        categories={"go_to_place": accept_any}, stubborn_refresh=refresh, stubborn_minimum=86_400
    )
    run = running(config=config, stubborn=1.0)
    run.child_end()
    assert run.state.stubborn is not None and run.state.stubborn.period == 86_400
    for step in (0, 1, 10**6, 10**15):
        run.tick(now=run.now + step)


@pytest.mark.parametrize(
    ("field", "value", "problem"),
    [
        ("id_policy", "bogus", "expected one of ['goal', 'adapter']"),
        ("compatibility", 3, "expected one of ['standard', 'rmf_ros2']"),
        ("max_description_length", 0, "expected a positive integer of at most 1000000 (bytes)"),
        ("max_description_length", True, "expected a positive integer of at most 1000000 (bytes)"),
        ("max_description_length", 2.5, "expected a positive integer of at most 1000000 (bytes)"),
        ("max_description_length", 1_000_001, "expected a positive integer of at most 1000000 (bytes)"),
    ],
)
def test_other_settings_name_the_field(field: str, value: Any, problem: str) -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(**_kwargs(field, value))
    assert str(caught.value) == f"ServerConfig.{field}: {problem} (got {value!r})"


@pytest.mark.parametrize(
    ("value", "kept"), [(0.001, 0.01), (0.01, 0.01), (1, 1.0), (0.5, 0.5), (10**6, 1e6)], ids=repr
)
def test_move_threshold_is_at_least_a_centimetre(value: float, kept: float) -> None:
    threshold = ServerConfig(stubborn_move_threshold=value).stubborn_move_threshold
    assert threshold == kept
    assert type(threshold) is float


@pytest.mark.parametrize("field", ["stubborn_minimum", "stubborn_refresh"])
@pytest.mark.parametrize("value", [0.001, 1, 2.5, 86_400])  # the bounds of R0.1 and between
def test_small_positive_periods_are_kept(field: str, value: float) -> None:
    assert getattr(ServerConfig(**_kwargs(field, value)), field) == value


def test_server_config_is_keyword_only() -> None:
    with pytest.raises(TypeError):
        ServerConfig({"dock": accept_any})  # type: ignore[call-arg]


def test_server_config_compares_and_hashes_by_identity() -> None:
    # A config holds validators (functions) and a dict: it is hashable by identity,
    # so it can key a cache or sit in a set, and two configs are never "equal".
    first, second = ServerConfig(), ServerConfig()
    alias = first
    assert first == alias
    assert first != second
    assert len({first, second, first}) == 2
    assert {CONFIG: 1}[CONFIG] == 1


def test_validator_type_alias() -> None:
    assert machine.Validator == Callable[[str, Any], Sequence[str]]
    hints = typing.get_type_hints(ServerConfig)
    assert hints["categories"] == Mapping[str, Callable[[str, Any], Sequence[str]]]


def test_handler_table_type() -> None:
    hints = typing.get_type_hints(machine)
    handler = Callable[[State, Any, ServerConfig], Transition]
    assert hints["HANDLERS"] == Mapping[str, handler]


# --------------------------------------------------------------------------- state classes


@pytest.mark.parametrize(
    "build",
    [
        lambda: QueuedGoal(u(1), next_goal(1, 5)),  # type: ignore[call-arg]
        lambda: RunningGoal(u(1), next_goal(1, 5), 5, "underway", True),  # type: ignore[call-arg]
        lambda: Position("L1", 0.0, 0.0),  # type: ignore[call-arg]
        lambda: Stubbornness(2.0, 0, 0, None),  # type: ignore[call-arg]
        lambda: State(FLEET, ROBOT),  # type: ignore[call-arg]
    ],
    ids=["QueuedGoal", "RunningGoal", "Position", "Stubbornness", "State"],
)
def test_state_classes_are_keyword_only(build: Callable[[], object]) -> None:
    with pytest.raises(TypeError):
        build()


@pytest.mark.parametrize("build", [lambda: State.new(FLEET, ROBOT), lambda: State(fleet=FLEET, robot=ROBOT)])
def test_initial_state_is_the_spec_table(build: Callable[[], State]) -> None:
    # docs/spec.md section 0, "State": the initial column
    state = build()
    assert attrs.asdict(state, recurse=False) == {
        "fleet": FLEET,
        "robot": ROBOT,
        "seq": 0,
        "active": False,
        "event_id": 0,
        "description": "",
        "status": "uninitialized",
        "last_id": 0,
        "running": None,
        "queued": (),
        "cancels": (),
        "interrupted": False,
        "task_signal": "",
        "stubborn": None,
        "position": None,
        "log_seq": 0,
        "shutdown": False,
    }
    assert state.phase is DynamicState.INACTIVE
    assert state.current_id == 0


@pytest.mark.parametrize(
    ("fleet", "robot", "field", "value"),
    [("1fleet", ROBOT, "fleet", "1fleet"), (FLEET, "r__1", "robot", "r__1"), ("a/b", "c/d", "fleet", "a/b")],
)
def test_new_state_names_the_bad_token(fleet: str, robot: str, field: str, value: str) -> None:
    with pytest.raises(InvalidName) as caught:
        State.new(fleet, robot)
    assert caught.value.field == field
    assert caught.value.value == value
    assert str(caught.value).startswith(f"{field} name {value!r} is not a valid ROS 2 name token: ")


# --------------------------------------------------------------------------- R6.2: uint64 adapter ids


@pytest.mark.spec("R6.2", "R17.3")
@pytest.mark.parametrize(
    ("last_id", "child_id"),
    [(200, 201), (2**63, 2**63 + 1), (2**64 - 2, 2**64 - 1), (2**64 - 1, 0)],
)
def test_adapter_ids_count_modulo_2_64(last_id: int, child_id: int) -> None:
    run = waiting(event_id=last_id, config=ADAPTER)
    outputs = run.submit(u(1), next_goal(1, 0))
    assert start_child(child_id) in outputs
    assert run.state.last_id == child_id
    assert run.state.running is not None
    assert run.state.running.child_id == child_id


# --------------------------------------------------------------------------- R7.3: log entries


@pytest.mark.spec("R7.3", "R13.1")
def test_signal_log_time_is_whole_milliseconds() -> None:
    run = running(child_id=5)
    now = T0 + 999_999  # 100 s and 0.999999 ms
    outputs = run.task_cancel(now=now)
    log = outputs[0]
    assert isinstance(log, outs.Log)
    assert log.entry == entry(0, "info", now, "Received signal to cancel")
    assert log.entry.unix_millis_time == 100_000
    assert type(log.entry.unix_millis_time) is int


@pytest.mark.spec("R7.3", "R12.2")
def test_clamp_log_entry_time_and_text() -> None:
    run = waiting()
    now = T0 + 1_500_000  # 1.5 ms past T0
    outputs = run.submit(u(1), next_goal(1, 5, stubborn=0.5), now=now)
    log = outputs[2]
    assert isinstance(log, outs.Log)
    assert log.entry == entry(
        0, "warning", now, "stubborn_period 0.5 s is below the minimum of 2 s; 2 s will be used"
    )
    assert type(log.entry.unix_millis_time) is int
    assert log.entry.unix_millis_time == 100_001


@pytest.mark.spec("R12.2")
def test_clamp_text_uses_the_configured_minimum() -> None:
    run = waiting(config=attrs.evolve(CONFIG, stubborn_minimum=2.5))
    outputs = run.submit(u(1), next_goal(1, 5, stubborn=1.25))
    log = outputs[2]
    assert isinstance(log, outs.Log)
    assert log.entry.text == "stubborn_period 1.25 s is below the minimum of 2.5 s; 2.5 s will be used"


# --------------------------------------------------------------------------- R4: rejection sentences


def _shut_down() -> Run:
    run = waiting()
    run.shutdown()
    return run


@pytest.mark.spec("R4.15")
@pytest.mark.parametrize(
    ("build", "sent", "reason", "text"),
    [
        (_shut_down, next_goal(1, 2), R.SHUTTING_DOWN, "the server is shutting down"),
        (waiting, next_goal(7, 2), R.SEQ_MISMATCH, "Expected 1, received 7"),
        (Run, next_goal(0, 2), R.INACTIVE, "no dynamic event is active for this robot"),
        (
            waiting,
            goal(1, 0),
            R.UNINITIALIZED_EVENT_TYPE,
            "event_type is 0 (UNINITIALIZED): the goal was default-initialized",
        ),
        (
            waiting,
            goal(1, 4),
            R.UNKNOWN_EVENT_TYPE,
            "event_type 4 is none of NEXT (1), CANCEL (2), FINISHED (3)",
        ),
        (running, next_goal(1, 6), R.BUSY, "event 5 is running: only a CANCEL with its id is accepted"),
        (
            waiting,
            next_goal(1, 2, category="dock"),
            R.UNSUPPORTED_CATEGORY,
            "category 'dock' is not supported; supported: go_to_place, perform_action",
        ),
        (
            lambda: waiting(config=ServerConfig()),
            next_goal(1, 2),
            R.UNSUPPORTED_CATEGORY,
            "category 'go_to_place' is not supported; supported: none",
        ),
        (
            lambda: waiting(config=attrs.evolve(CONFIG, max_description_length=4)),
            next_goal(1, 2, description='"abc"'),
            R.DESCRIPTION_INVALID,
            "description is 5 bytes, above the limit of 4",
        ),
        (
            waiting,
            next_goal(1, 2, description='{"place": 3}'),
            R.DESCRIPTION_INVALID,
            "the description does not fit the 'go_to_place' category: "
            "expected a place name or an object with a string 'place'",
        ),
        (
            waiting,
            next_goal(1, 2, stubborn=math.nan),
            R.NON_FINITE_STUBBORN_PERIOD,
            "stubborn_period nan is not a finite number",
        ),
        (
            waiting,
            next_goal(1, 2, stubborn=-math.inf),
            R.NON_FINITE_STUBBORN_PERIOD,
            "stubborn_period -inf is not a finite number",
        ),
        (waiting, next_goal(1, 1), R.STALE_ID, "id 1 is not greater than 1, the highest id used in this run"),
        (
            lambda: waiting().evolve(last_id=U64_MAX),
            next_goal(1, 0),
            R.STALE_ID,
            f"id 0 asks the server for the next id, and none is left above {U64_MAX}",
        ),
        (waiting, cancel_goal(1, 5), R.CANCEL_IDLE, "no event is running to cancel"),
        (running, cancel_goal(1, 6), R.CANCEL_ID_MISMATCH, "the running event is 5, the CANCEL names 6"),
    ],
    ids=[
        "shutting_down",
        "seq_mismatch",
        "inactive",
        "uninitialized_event_type",
        "unknown_event_type",
        "busy",
        "unsupported_category",
        "unsupported_category_none",
        "too_long",
        "validator",
        "nan_period",
        "infinite_period",
        "stale_id",
        "stale_id_none_left",
        "cancel_idle",
        "cancel_id_mismatch",
    ],
)
def test_rejection_sentences(build: Callable[[], Run], sent: Any, reason: RejectReason, text: str) -> None:
    rejection = _rejection(build().request(u(9), sent))
    assert rejection.reason is reason
    assert rejection.text == text


@pytest.mark.spec("R4.8")
def test_too_long_errors_and_failure_string() -> None:
    run = waiting(config=attrs.evolve(CONFIG, max_description_length=4))
    rejection = _rejection(run.request(u(9), next_goal(1, 2, description='"abc"')))
    problem = "description is 5 bytes, above the limit of 4"
    assert rejection.errors == (problem,)
    assert rejection.execution_failure == f"{PARSE_FAILURE}\n -- {problem}"


@pytest.mark.spec("R4.9")
def test_not_json_sentence_names_the_category() -> None:
    run = waiting()
    rejection = _rejection(run.request(u(9), next_goal(1, 2, category="perform_action", description="{")))
    assert rejection.reason is R.DESCRIPTION_NOT_JSON
    (error,) = rejection.errors
    assert error.startswith("not valid JSON: ")
    assert rejection.text == f"the description of the 'perform_action' event is {error}"
    assert rejection.execution_failure == f"{PARSE_FAILURE}\n -- {error}"


@pytest.mark.spec("R4.10")
def test_several_validator_errors_are_joined_in_the_sentence() -> None:
    def two_errors(category: str, description: Any) -> Sequence[str]:
        return ["first problem", "second problem"]

    run = waiting(config=ServerConfig(categories={"dock": two_errors}))
    rejection = _rejection(run.request(u(9), next_goal(1, 2, category="dock", description="{}")))
    assert rejection.text == "the description does not fit the 'dock' category: first problem; second problem"


@pytest.mark.spec("R4.10")
def test_a_raising_validator_is_one_error_naming_the_exception() -> None:
    def broken(category: str, description: Any) -> Sequence[str]:
        raise KeyError("schema")

    run = waiting(config=ServerConfig(categories={"dock": broken}))
    rejection = _rejection(run.request(u(9), next_goal(1, 2, category="dock", description="{}")))
    error = "the validator raised KeyError: 'schema'"
    assert rejection.errors == (error,)
    assert rejection.text == f"the description does not fit the 'dock' category: {error}"
    assert rejection.execution_failure == f"{PARSE_FAILURE}\n -- {error}"


@pytest.mark.spec("R6.1")
def test_a_category_dropped_before_the_start_aborts_with_one_error_line() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 5))
    run.config = ServerConfig(categories={"perform_action": accept_any, "dock": accept_any})
    assert run.start(u(1)) == (
        outs.ExecuteGoal(goal_uuid=u(1)),
        aborted(
            u(1),
            f"{PARSE_FAILURE}\n -- category 'go_to_place' is not supported; supported: dock, perform_action",
        ),
    )


# --------------------------------------------------------------------------- R18: Ignored sentences


def _ignored_why(outputs: tuple[Any, ...], kind: str) -> str:
    assert len(outputs) == 1
    (notice,) = outputs
    assert isinstance(notice, outs.Ignored)
    assert notice.input == kind
    return notice.why


def _signalled(kind: str) -> Run:
    run = running()  # a started child keeps the run active after the signal (R13.2)
    if kind == "kill":
        run.task_kill()
    else:
        run.task_cancel()
    return run


@pytest.mark.spec("R18.1", "R18.2", "R18.3", "R18.4", "R18.5", "R18.6", "R18.7")
@pytest.mark.parametrize(
    ("build", "event", "why"),
    [
        (_shut_down, ins.Begin(description="{}", event_id=1, now=T0), "the server is shutting down"),
        (waiting, ins.Begin(description="{}", event_id=2, now=T0), "a dynamic event is already active"),
        (
            running,
            ins.GoalRequested(goal_uuid=u(1), goal=next_goal(1, 6), now=T0),
            "a goal with this uuid is already open",
        ),
        (
            waiting,
            ins.GoalStarted(goal_uuid=u(7), now=T0),
            "no accepted goal with this uuid is waiting to start",
        ),
        (waiting, ins.ChildProgress(status="underway", now=T0), "no child event is running"),
        (deferred, ins.ChildProgress(status="underway", now=T0), "no child event is running"),
        (waiting, ins.ChildFinished(status="completed", now=T0), "no child event is running"),
        (deferred, ins.ChildFinished(status="completed", now=T0), "no child event is running"),
        (Run, ins.Interrupt(now=T0), "no dynamic event is active"),
        (deferred, ins.Interrupt(now=T0), "the task is already interrupted"),
        (waiting, ins.Resume(now=T0), "the task is not interrupted"),
        (Run, ins.TaskCancel(now=T0), "no dynamic event is active"),
        (Run, ins.TaskKill(now=T0), "no dynamic event is active"),
        (lambda: _signalled("cancel"), ins.TaskCancel(now=T0), "the task was already canceled"),
        (lambda: _signalled("kill"), ins.TaskCancel(now=T0), "the task was already killed"),
        (lambda: _signalled("kill"), ins.TaskKill(now=T0), "the task was already killed"),
        (_shut_down, ins.Shutdown(now=T0), "the server is already shutting down"),
    ],
    ids=[
        "begin-after-shutdown",
        "begin-while-active",
        "duplicate-uuid",
        "unknown-start",
        "progress-idle",
        "progress-deferred",
        "end-idle",
        "end-deferred",
        "interrupt-inactive",
        "interrupt-twice",
        "resume-not-interrupted",
        "cancel-inactive",
        "kill-inactive",
        "cancel-twice",
        "cancel-after-kill",
        "kill-twice",
        "shutdown-twice",
    ],
)
def test_ignored_sentences(build: Callable[[], Run], event: ins.Input, why: str) -> None:
    run = build()
    before = run.state
    assert _ignored_why(run.step(event), event.KIND) == why
    assert run.state == before


# --------------------------------------------------------------------------- R14.5, R19.7


@pytest.mark.spec("R14.5", "R19.7")
def test_a_deferred_child_whose_description_no_longer_parses_still_starts() -> None:
    # Unreachable through accept (R6.1 parsed it), but a state built by hand or
    # edited in a snapshot may hold one: the machine must not raise, and the
    # child starts with no parsed description.
    run = deferred(child_id=5)
    assert run.state.running is not None
    broken = attrs.evolve(run.state.running, goal=next_goal(1, 5, description="{"))
    run.evolve(running=broken)
    outputs = run.resume()
    assert outputs[0] == outs.StartChild(category="go_to_place", description="{", id=5, parsed=None)
    assert outputs[0].parsed is None


@pytest.mark.spec("R14.5")
def test_a_deferred_child_with_a_null_description_starts_with_none() -> None:
    run = waiting(config=ServerConfig(categories={"perform_action": accept_any}))
    run.interrupt()
    run.submit(u(1), next_goal(1, 5, category="perform_action", description="null"))
    outputs = run.resume()
    assert outputs[0] == outs.StartChild(category="perform_action", description="null", id=5, parsed=None)


# --------------------------------------------------------------------------- the transition table


def _all_kinds() -> list[str]:
    return sorted(machine.HANDLERS)


_EXPECTED_TARGETS: dict[tuple[DynamicState, str], set[DynamicState]] = {
    (DynamicState.INACTIVE, "begin"): {DynamicState.WAITING},
    (DynamicState.WAITING, "goal_started"): {DynamicState.RUNNING, DynamicState.INACTIVE},
    (DynamicState.WAITING, "goal_submitted"): {DynamicState.RUNNING, DynamicState.INACTIVE},
    (DynamicState.WAITING, "task_cancel"): {DynamicState.INACTIVE},
    (DynamicState.WAITING, "task_kill"): {DynamicState.INACTIVE},
    (DynamicState.WAITING, "shutdown"): {DynamicState.INACTIVE},
    (DynamicState.RUNNING, "child_finished"): {DynamicState.WAITING, DynamicState.INACTIVE},
    (DynamicState.RUNNING, "goal_started"): {DynamicState.WAITING},
    (DynamicState.RUNNING, "goal_submitted"): {DynamicState.WAITING},
    (DynamicState.RUNNING, "cancel_requested"): {DynamicState.WAITING},
    (DynamicState.RUNNING, "task_cancel"): {DynamicState.INACTIVE},
    (DynamicState.RUNNING, "task_kill"): {DynamicState.INACTIVE},
    (DynamicState.RUNNING, "shutdown"): {DynamicState.INACTIVE},
    (DynamicState.RUNNING, "restart"): {DynamicState.WAITING, DynamicState.INACTIVE},
}


@pytest.mark.spec("R2.1")
@pytest.mark.parametrize("source", list(DynamicState), ids=lambda phase: phase.name)
def test_allowed_targets_per_phase_and_input(source: DynamicState) -> None:
    for kind in _all_kinds():
        expected = {source} | _EXPECTED_TARGETS.get((source, kind), set())
        assert allowed_targets(source, kind) == frozenset(expected), (source.name, kind)


def test_every_edge_names_a_real_input_and_a_rule() -> None:
    rules = set(re.findall(r"\*\*(R\d+\.\d+)\*\*", SPEC))
    for edge in machine.TRANSITIONS:
        assert edge.input in machine.HANDLERS, edge
        cited = re.findall(r"R\d+\.\d+", edge.rule)
        assert cited, edge
        assert set(cited) <= rules, edge
    assert len(machine.TRANSITIONS) == 18


def test_spec_diagram_is_the_transition_table() -> None:
    # Appendix A of docs/spec.md is generated from TRANSITIONS: inputs, guards and rules
    block = SPEC.split("<!-- diagram:start -->\n", 1)[1].split("<!-- diagram:end -->", 1)[0]
    assert block == f"```mermaid\n{render('mermaid')}```\n"
    for edge in machine.TRANSITIONS:
        label = edge.input if not edge.guard else f"{edge.input} [{edge.guard}]"
        assert f"    {edge.source.name} --> {edge.target.name}: {label} ({edge.rule})\n" in block


@pytest.mark.spec("R2.1", "R11.1")
def test_a_finished_start_is_a_declared_edge() -> None:
    run = waiting()
    run.submit(u(1), finished_goal(1))
    assert run.phase in allowed_targets(DynamicState.WAITING, "goal_started")
    assert run.phase is DynamicState.INACTIVE


# --------------------------------------------------------------------------- survivors of the split layout


def test_the_dynamic_event_category_is_refused_naming_the_field() -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(categories={"dynamic_event": machine.accept_any})
    assert caught.value.field == "categories" and caught.value.value == "dynamic_event"
    assert caught.value.problem == (
        "'dynamic_event' can never be a child category: a nested run would break the outer one"
    )


def test_the_smallest_description_limit_is_one_byte() -> None:
    assert ServerConfig(max_description_length=1).max_description_length == 1


@pytest.mark.parametrize("seconds", [1, 86_400])
def test_whole_seconds_become_floats_up_to_the_bound(seconds: int) -> None:
    config = ServerConfig(stubborn_minimum=seconds, stubborn_refresh=seconds)
    assert type(config.stubborn_minimum) is float and type(config.stubborn_refresh) is float


def test_a_zero_period_is_refused_as_given() -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(stubborn_minimum=0)
    assert type(caught.value.value) is int and str(caught.value).endswith("(got 0)")


@pytest.mark.spec("R17.1", "R4.16")
@pytest.mark.parametrize(
    ("event_type", "id", "running", "rule"),
    [
        (EventType.NEXT, 0, False, "R4.16"),
        (EventType.FINISHED, 0, False, "R4.16"),
        (0, 0, False, "R17.1"),
        (4, 0, False, "R17.1"),
        (EventType.CANCEL, 5, False, "R17.1"),
        (EventType.CANCEL, 6, True, "R17.1"),
        (EventType.CANCEL, 5, True, "R4.16"),
    ],
)
def test_an_acceptance_names_the_rule_that_lets_the_goal_in(
    event_type: int, id: int, running: bool, rule: str
) -> None:
    config = ServerConfig.rmf_ros2({"go_to_place": machine.accept_any})
    state = _rmf_state(running)
    goal = Goal(
        dynamic_event_seq=state.seq, event_type=event_type, id=id, category="go_to_place", description="1"
    )
    decision = machine.accept(state, goal, config)
    assert isinstance(decision, outs.Accepted) and decision.rule == rule


def _rmf_state(running: bool) -> State:
    """An active run of seq 1, with child 5 running or not."""
    status = DynamicEventStatus(
        dynamic_event_seq=1,
        dynamic_state=DynamicState.RUNNING if running else DynamicState.WAITING,
        status="underway" if running else "standby",
        id=5 if running else 4,
    )
    return machine.state_from_status(status)


# --------------------------------------------------------------------------- R5.2, R5.3: how a race was lost


def _finished() -> Run:
    run = waiting()
    run.request(u(2), finished_goal(1))
    run.start(u(2))
    return run


def _id_taken() -> Run:
    run = waiting()
    run.request(u(2), next_goal(1, 6))
    run.start(u(2))
    run.child_end()
    return run


@pytest.mark.spec("R5.2")
@pytest.mark.parametrize(
    ("build", "sent", "text"),
    [
        (lambda: waiting(seq=1), next_goal(1, 6), "its seq 1 is no longer the run's seq 2"),
        (_finished, next_goal(1, 6), "no dynamic event is active any more"),
        (running, next_goal(1, 6), "event 5 holds the running slot"),
        (_id_taken, next_goal(1, 6), "its id 6 is no longer above 6, the highest id used"),
        (waiting, next_goal(1, 6), ""),
    ],
    ids=["seq", "inactive", "running", "id", "not_lost"],
)
def test_race_lost_sentences(build: Callable[[], Run], sent: Goal, text: str) -> None:
    run = build()
    assert machine.race_lost(run.state, sent, run.config) == text


@pytest.mark.spec("R5.3")
def test_a_submitted_goal_that_lost_a_race_is_aborted_with_the_refusal_under_the_failure() -> None:
    assert waiting().step(ins.GoalSubmitted(goal_uuid=u(2), goal=next_goal(7, 6), now=T0)) == (
        outs.ExecuteGoal(goal_uuid=u(2)),
        aborted(u(2), "race condition\n -- Expected 1, received 7"),
    )
