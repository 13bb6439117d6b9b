"""§17. rmf_ros2 compatibility: the tests of the rules of docs/spec.md §17.

The section's conformance vectors are src/dynevent/conformance/vectors/compat-rmf_ros2.json.
"""

from __future__ import annotations

import math

import attrs
import pytest

from dynevent.errors import InvalidValue
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import (
    ServerConfig,
    State,
)
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import Compatibility, DynamicState, EventType, IdPolicy, RejectReason
from support.scenario import (
    CANCEL_ID,
    CATEGORIES,
    CONFIG,
    IDLE_CANCEL,
    INVALID_EVENT_TYPE,
    RACE,
    RMF_ROS2,
    RUNNING,
    WAITING,
    Run,
    aborted,
    cancel_goal,
    execute,
    feedback,
    goal,
    next_goal,
    rejected,
    running,
    start_child,
    status,
    u,
    waiting,
)

R = RejectReason


def _accepted(uuid: str) -> tuple[outs.GoalAccepted]:
    return (outs.GoalAccepted(goal_uuid=uuid),)


def _rmf_state(running: bool) -> State:
    """An active run of seq 1, with child 5 running or not."""
    status = DynamicEventStatus(
        dynamic_event_seq=1,
        dynamic_state=DynamicState.RUNNING if running else DynamicState.WAITING,
        status="underway" if running else "standby",
        id=5 if running else 4,
    )
    return machine.state_from_status(status)


# --------------------------------------------------------------------------- R17.1


@pytest.mark.spec("R17.1", "R17.2")
@pytest.mark.parametrize("event_type", [0, 4, 2**32 - 1])
def test_bad_event_types_are_accepted_then_aborted(event_type: int) -> None:
    run = waiting(config=RMF_ROS2)
    assert run.request(u(9), goal(1, event_type, id=2)) == _accepted(u(9))
    assert run.start(u(9)) == (execute(u(9)), aborted(u(9), INVALID_EVENT_TYPE))
    assert run.state == attrs.evolve(run.before, queued=())


@pytest.mark.spec("R17.1", "R17.2", "R9.1")
def test_an_idle_cancel_is_accepted_then_aborted() -> None:
    run = waiting(config=RMF_ROS2)
    assert run.request(u(9), cancel_goal(1, 1)) == _accepted(u(9))
    assert run.start(u(9)) == (execute(u(9)), aborted(u(9), IDLE_CANCEL))


@pytest.mark.spec("R17.1", "R17.2", "R9.2")
def test_a_cancel_with_the_wrong_id_is_accepted_then_aborted() -> None:
    run = running(config=RMF_ROS2, event_id=10)
    assert run.state.running is not None
    assert run.state.running.child_id == 11
    assert run.request(u(9), cancel_goal(1, 5)) == _accepted(u(9))
    assert run.start(u(9)) == (execute(u(9)), aborted(u(9), CANCEL_ID))
    assert run.phase is RUNNING
    assert run.state.running is not None
    assert not run.state.running.canceling


@pytest.mark.spec("R17.1", "R4.6")
@pytest.mark.parametrize("event_type", [0, 7])
def test_bad_event_types_while_busy_are_busy_in_rmf_ros2_mode(event_type: int) -> None:
    run = running(config=RMF_ROS2, event_id=10)
    assert run.request(u(9), goal(1, event_type, id=11)) == (rejected(u(9), R.BUSY, current_id=11),)


@pytest.mark.spec("R17.1", "R4.2", "R4.3", "R4.7", "R4.9", "R4.11")
def test_the_other_checks_still_apply_in_rmf_ros2_mode() -> None:
    run = Run(RMF_ROS2)
    assert run.request(u(9), goal(0, 7))[0].rejection.reason is R.INACTIVE
    run.begin(event_id=10)
    assert run.request(u(9), goal(0, 7))[0].rejection.reason is R.SEQ_MISMATCH
    assert run.request(u(9), next_goal(1, 0, category="dock"))[0].rejection.reason is R.UNSUPPORTED_CATEGORY
    assert run.request(u(9), next_goal(1, 0, description="{"))[0].rejection.reason is R.DESCRIPTION_NOT_JSON
    assert (
        run.request(u(9), next_goal(1, 0, stubborn=math.nan))[0].rejection.reason
        is R.NON_FINITE_STUBBORN_PERIOD
    )


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
    config = ServerConfig.rmf_ros2({"go_to_place": machine.any_description})
    state = _rmf_state(running)
    goal = Goal(
        dynamic_event_seq=state.seq, event_type=event_type, id=id, category="go_to_place", description="1"
    )
    decision = machine.accept(state, goal, config)
    assert isinstance(decision, outs.Accepted) and decision.rule == rule


# --------------------------------------------------------------------------- R17.2


@pytest.mark.spec("R17.2", "R5.2")
def test_a_bad_event_type_that_lost_the_race_is_a_race() -> None:
    run = waiting(config=RMF_ROS2)
    run.request(u(9), goal(1, 0))
    run.submit(u(1), next_goal(1, 0))
    assert run.start(u(9)) == (execute(u(9)), aborted(u(9), RACE))


# --------------------------------------------------------------------------- R17.3


@pytest.mark.spec("R17.3")
def test_the_rmf_ros2_configuration_sets_mode_and_policy() -> None:
    config = ServerConfig.rmf_ros2(CATEGORIES)
    assert (config.compatibility, config.id_policy) == (Compatibility.RMF_ROS2, IdPolicy.ADAPTER)
    assert set(config.categories) == set(CATEGORIES)
    assert (CONFIG.compatibility, CONFIG.id_policy) == (Compatibility.STANDARD, IdPolicy.GOAL)


@pytest.mark.spec("R17.3", "R6.2", "R4.12")
def test_the_server_numbers_children_in_rmf_ros2_mode() -> None:
    run = waiting(event_id=10, config=RMF_ROS2)
    assert run.submit(u(1), next_goal(1, 0)) == (
        execute(u(1)),
        start_child(11),
        feedback(u(1), "underway", 11),
        status(1, RUNNING, "underway", 11),
    )
    run.child_end("completed")
    assert run.submit(u(2), next_goal(1, 3))[1] == start_child(12)
    assert run.state.last_id == 12


@pytest.mark.spec("R17.3", "R4.14")
def test_adapter_policy_in_standard_mode_checks_cancels_against_the_servers_id() -> None:
    run = running(child_id=99, config=attrs.evolve(CONFIG, id_policy=IdPolicy.ADAPTER), event_id=10)
    assert run.request(u(9), cancel_goal(1, 99)) == (
        rejected(u(9), R.CANCEL_ID_MISMATCH, current_id=11, requested_id=99, execution_failure=CANCEL_ID),
    )
    assert run.request(u(8), cancel_goal(1, 11)) == _accepted(u(8))


@pytest.mark.spec("R17.8")
def test_an_id_the_adapter_draws_puts_the_next_child_above_it() -> None:
    """rmf_ros2's go_to_place child draws a second id for its plan: the run's children come 1, 3, 5."""
    run = waiting(event_id=0, config=RMF_ROS2)
    run.submit(u(1), next_goal(run.seq, 0))
    assert run.state.running is not None and run.state.running.child_id == 1
    assert run.id_drawn() == ()  # while the child runs the status names it: nothing to publish
    assert run.state.last_id == 2
    run.child_end()
    run.submit(u(2), next_goal(run.seq, 0))
    assert run.state.running is not None and run.state.running.child_id == 3


@pytest.mark.spec("R17.8", "R2.2", "R2.3")
def test_an_id_drawn_while_waiting_shows_in_the_status_and_wraps_as_the_counter_does() -> None:
    run = waiting(event_id=4, config=RMF_ROS2)
    assert run.id_drawn() == (status(run.seq, WAITING, "standby", 5, now=run.now),)
    top = Run(RMF_ROS2, attrs.evolve(run.state, last_id=2**64 - 1), now=run.now)
    top.id_drawn()
    assert top.state.last_id == 0  # the adapter's counter wraps, as its children's ids do (R6.2)


@pytest.mark.spec("R17.8", "R19.8")
def test_a_state_whose_adapter_drew_ids_under_the_running_child_restores() -> None:
    from dynevent.server import snapshot

    run = waiting(event_id=0, config=RMF_ROS2)
    run.submit(u(1), next_goal(run.seq, 0))
    run.id_drawn()
    restored = snapshot.loads(snapshot.dumps(run.state))
    assert restored == run.state and restored.last_id == 2 and restored.current_id == 1


@pytest.mark.spec("R17.8", "R14.5")
def test_an_id_drawn_under_a_deferred_child_keeps_its_id_and_the_model_agrees() -> None:
    """A child deferred by an interruption has its id when it is deferred; an id the adapter draws
    meanwhile does not change it, and the next child comes above the drawn id.  The reference model
    once lowered its highest id to the deferred child's at the resume."""
    from dynevent.server import inputs as ins
    from dynevent.testing import Observer

    run = waiting(event_id=0, config=RMF_ROS2)
    observer = Observer(run.state.fleet, run.state.robot, RMF_ROS2)
    steps = [
        ins.Interrupt(now=run.now),
        ins.GoalRequested(goal_uuid=u(1), goal=next_goal(run.seq, 0), now=run.now),
        ins.GoalStarted(goal_uuid=u(1), now=run.now),
        ins.IdDrawn(now=run.now),
        ins.Resume(now=run.now),
        ins.ChildFinished(status="completed", now=run.now),
        ins.GoalRequested(goal_uuid=u(2), goal=next_goal(run.seq, 0), now=run.now),
        ins.GoalStarted(goal_uuid=u(2), now=run.now),
    ]
    fresh = Run(RMF_ROS2, now=run.now)
    for event in [ins.Begin(description="{}", event_id=0, now=run.now), *steps]:
        observer.observe(event, fresh.step(event))
    assert fresh.state.running is not None and fresh.state.running.child_id == 3


def _published(description: str) -> str:
    begin = Run(RMF_ROS2).begin(event_id=1, description=description)[0]
    assert isinstance(begin, outs.PublishBegin)
    return begin.message.description


@pytest.mark.spec("R17.6")
def test_the_re_serialised_text_is_utf8_with_only_the_escapes_json_needs() -> None:
    given = (
        r'{"z": 1, "é": {"b": 2, "a": 1}, "E": "caf\u00e9 \ud83d\ude00 \u2028 \/ \u007f",'
        r' "e": "\"q\" \\ \u0001 \u001F \t \n \r \b \f"}'
    )
    assert _published(given) == (
        '{"E":"café 😀 \u2028 / \u007f","e":"\\"q\\" \\\\ \\u0001 \\u001f \\t \\n \\r \\b \\f",'
        '"z":1,"é":{"a":1,"b":2}}'
    )


@pytest.mark.spec("R17.6", "R1.5", "R1.3")
def test_the_re_serialised_text_nests_as_deep_as_the_given_and_no_deeper_than_64_levels() -> None:
    deepest = '{"parameters": ' + "[" * 63 + "{}" + "]" * 63 + "}"  # the object, 63 arrays, {}: 65
    with pytest.raises(InvalidValue, match="nested deeper than 64 levels"):
        ins.Begin(description=deepest, event_id=1, now=0)
    deepest = '{"parameters": ' + "[" * 62 + "{}" + "]" * 62 + "}"  # 64 levels
    assert _published(deepest) == '{"parameters":' + "[" * 62 + "{}" + "]" * 62 + "}"
    scalars = '{"parameters": ' + "[" * 63 + '"x", 1' + "]" * 63 + "}"  # a scalar adds no level
    assert _published(scalars) == '{"parameters":' + "[" * 63 + '"x",1' + "]" * 63 + "}"


@pytest.mark.spec("R17.6")
def test_integers_are_written_in_decimal_whatever_their_size() -> None:
    assert _published('{"a": 10000000000000000000000, "b": -0, "c": 7}') == (
        '{"a":10000000000000000000000,"b":0,"c":7}'
    )
