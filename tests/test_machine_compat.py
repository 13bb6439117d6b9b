"""docs/spec.md sections 17 (rmf_ros2 compatibility) and 18 (inputs without effect)."""

from __future__ import annotations

import math

import attrs
import pytest

from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig
from dynevent.wire.vocab import Compatibility, IdPolicy, RejectReason
from scenario import (
    CANCEL_ID,
    CATEGORIES,
    CONFIG,
    IDLE_CANCEL,
    INVALID_EVENT_TYPE,
    RACE,
    RMF_ROS2,
    RUNNING,
    Run,
    aborted,
    cancel_goal,
    deferred,
    feedback,
    finished_goal,
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


def _execute(uuid: str) -> outs.ExecuteGoal:
    return outs.ExecuteGoal(goal_uuid=uuid)


# --------------------------------------------------------------------------- R17.1, R17.2


@pytest.mark.spec("R17.1", "R17.2")
@pytest.mark.parametrize("event_type", [0, 4, 2**32 - 1])
def test_bad_event_types_are_accepted_then_aborted(event_type: int) -> None:
    run = waiting(config=RMF_ROS2)
    assert run.request(u(9), goal(1, event_type, id=2)) == _accepted(u(9))
    assert run.start(u(9)) == (_execute(u(9)), aborted(u(9), INVALID_EVENT_TYPE))
    assert run.state == attrs.evolve(run.before, queued=())


@pytest.mark.spec("R17.1", "R17.2", "R9.1")
def test_an_idle_cancel_is_accepted_then_aborted() -> None:
    run = waiting(config=RMF_ROS2)
    assert run.request(u(9), cancel_goal(1, 1)) == _accepted(u(9))
    assert run.start(u(9)) == (_execute(u(9)), aborted(u(9), IDLE_CANCEL))


@pytest.mark.spec("R17.1", "R17.2", "R9.2")
def test_a_cancel_with_the_wrong_id_is_accepted_then_aborted() -> None:
    run = running(config=RMF_ROS2, event_id=10)
    assert run.state.running is not None
    assert run.state.running.child_id == 11
    assert run.request(u(9), cancel_goal(1, 5)) == _accepted(u(9))
    assert run.start(u(9)) == (_execute(u(9)), aborted(u(9), CANCEL_ID))
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


@pytest.mark.spec("R17.2", "R5.2")
def test_a_bad_event_type_that_lost_the_race_is_a_race() -> None:
    run = waiting(config=RMF_ROS2)
    run.request(u(9), goal(1, 0))
    run.submit(u(1), next_goal(1, 0))
    assert run.start(u(9)) == (_execute(u(9)), aborted(u(9), RACE))


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
        _execute(u(1)),
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


# --------------------------------------------------------------------------- R18.1


@pytest.mark.spec("R18.1")
def test_begin_and_shutdown_after_shutdown_are_ignored() -> None:
    run = Run()
    run.shutdown()
    run.assert_ignored(run.begin(), "begin")
    run.assert_ignored(run.shutdown(), "shutdown")


# --------------------------------------------------------------------------- R18.2


@pytest.mark.spec("R18.2")
def test_a_request_for_an_open_uuid_is_ignored() -> None:
    run = running(child_id=5, uuid=u(1))
    run.submit(u(2), cancel_goal(1, 5))
    run.request(u(3), cancel_goal(1, 5))
    for uuid in (u(1), u(2), u(3)):
        # would be accepted, or rejected, with a fresh uuid: the open uuid decides
        run.assert_ignored(run.request(uuid, cancel_goal(1, 5)), "goal_requested")
        run.assert_ignored(run.request(uuid, next_goal(1, 6)), "goal_requested")


# --------------------------------------------------------------------------- R18.3


@pytest.mark.spec("R18.3")
def test_a_start_of_a_goal_that_is_not_queued_is_ignored() -> None:
    run = waiting()
    run.assert_ignored(run.start(u(1)), "goal_started")  # never requested
    run.request(u(2), next_goal(1, 1))  # rejected: id 1 is not above the run's id (R4.12)
    run.assert_ignored(run.start(u(2)), "goal_started")
    run.submit(u(3), next_goal(1, 5))
    run.assert_ignored(run.start(u(3)), "goal_started")  # already running


@pytest.mark.spec("R18.3", "R15.1")
def test_a_start_of_a_goal_answered_at_shutdown_is_ignored() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 5))
    run.shutdown()
    run.assert_ignored(run.start(u(1)), "goal_started")


# --------------------------------------------------------------------------- R18.4


@pytest.mark.spec("R18.4")
@pytest.mark.parametrize("situation", ["inactive", "waiting", "deferred", "ended"])
def test_child_reports_without_a_started_child_are_ignored(situation: str) -> None:
    if situation == "inactive":
        run = Run()
    elif situation == "waiting":
        run = waiting()
    elif situation == "deferred":
        run = deferred(child_id=5)
    else:
        run = running(child_id=5)
        run.child_end("completed")
    run.assert_ignored(run.progress("underway", log="hello"), "child_progress")
    run.assert_ignored(run.child_end("completed"), "child_finished")


# --------------------------------------------------------------------------- R18.5


@pytest.mark.spec("R18.5")
@pytest.mark.parametrize("ended", [False, True])
def test_interrupt_and_task_signals_while_inactive_are_ignored(ended: bool) -> None:
    run = Run()
    if ended:
        run = waiting()
        run.submit(u(1), finished_goal(1))
    run.assert_ignored(run.interrupt(), "interrupt")
    run.assert_ignored(run.task_cancel(), "task_cancel")
    run.assert_ignored(run.task_kill(), "task_kill")


# --------------------------------------------------------------------------- R18.6


@pytest.mark.spec("R18.6")
@pytest.mark.parametrize("situation", ["waiting", "running", "deferred"])
def test_interrupt_while_interrupted_is_ignored(situation: str) -> None:
    if situation == "deferred":
        run = deferred(child_id=5)
    else:
        run = waiting() if situation == "waiting" else running(child_id=5)
        run.interrupt()
    run.assert_ignored(run.interrupt(), "interrupt")


@pytest.mark.spec("R18.6")
@pytest.mark.parametrize("situation", ["inactive", "waiting", "running"])
def test_resume_while_not_interrupted_is_ignored(situation: str) -> None:
    run = Run() if situation == "inactive" else waiting() if situation == "waiting" else running()
    run.assert_ignored(run.resume(), "resume")


# --------------------------------------------------------------------------- R18.7


@pytest.mark.spec("R18.7", "R13.5")
def test_signals_after_a_kill_are_ignored_until_the_child_ends() -> None:
    run = running(child_id=5)
    run.task_cancel()
    run.task_kill()
    run.assert_ignored(run.task_cancel(), "task_cancel")
    run.assert_ignored(run.task_kill(), "task_kill")
    run.child_end("killed")
    # the run is over: now R18.5 applies
    run.assert_ignored(run.task_kill(), "task_kill")


# --------------------------------------------------------------------------- not ignored


@pytest.mark.spec("R18.1", "R12.3", "R16.1", "R14.3")
def test_ticks_queries_and_a_clearing_resume_are_not_ignored() -> None:
    run = Run()
    assert run.tick() == ()
    assert isinstance(run.query()[0], outs.DescriptionAnswer)
    run = waiting()
    run.interrupt()
    assert run.resume() == ()
    assert run.state != run.before
