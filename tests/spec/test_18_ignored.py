"""§18. Inputs without effect: the tests of the rules of docs/spec.md §18.

The section's conformance vectors are src/dynevent/conformance/vectors/18-ignored.json.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.holder import Execution
from support.scenario import (
    RMF_ROS2,
    T0,
    Run,
    cancel_goal,
    deferred,
    finished_goal,
    next_goal,
    running,
    running_server,
    shut_down,
    u,
    waiting,
)


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


# --------------------------------------------------------------------------- R18.1


@pytest.mark.spec("R18.1")
def test_begin_and_shutdown_after_shutdown_are_ignored() -> None:
    run = Run()
    run.shutdown()
    run.assert_ignored(run.begin(), "begin")
    run.assert_ignored(run.shutdown(), "shutdown")


@pytest.mark.spec("R18.1", "R12.3", "R16.1", "R14.3")
def test_ticks_queries_and_a_clearing_resume_are_not_ignored() -> None:
    run = Run()
    assert run.tick() == ()
    assert isinstance(run.query()[0], outs.DescriptionAnswer)
    run = waiting()
    run.interrupt()
    assert run.resume() == ()
    assert run.state != run.before


@pytest.mark.spec("R18.1", "R18.2", "R18.3", "R18.4", "R18.5", "R18.6", "R18.7")
@pytest.mark.parametrize(
    ("build", "event", "why"),
    [
        (shut_down, ins.Begin(description="{}", event_id=1, now=T0), "the server is shutting down"),
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
        (shut_down, ins.Shutdown(now=T0), "the server is already shutting down"),
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


@pytest.mark.spec("R18.4")
@pytest.mark.parametrize("automatic", [True, False])
def test_after_finishing_every_method_returns_nothing(automatic: bool) -> None:
    server = running_server()
    execution = Execution(server, 5, automatic_cancel=automatic)
    if automatic:
        execution.cancel(now=T0)
    else:
        execution.finished(now=T0)
    state = server.state
    calls: list[Callable[[], tuple[object, ...]]] = [
        lambda: execution.underway("x", now=T0),
        lambda: execution.delayed("x", now=T0),
        lambda: execution.blocked("x", now=T0),
        lambda: execution.error("x", now=T0),
        lambda: execution.finished(now=T0),
        lambda: execution.cancel(now=T0),
        lambda: execution.kill(now=T0),
    ]
    for call in calls:
        assert call() == ()
    assert server.state == state
    assert not execution.okay()
    execution.update_remaining_time(12.5)
    assert execution.remaining_time == 12.5
    assert "finished" in repr(execution)


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


@pytest.mark.spec("R18.8", "R18.1")
def test_an_id_drawn_under_the_goal_policy_or_while_inactive_is_ignored() -> None:
    """The NEXT goals name the children under id policy goal: an adapter's own ids are no business of
    the protocol's; and no run, no counter to move on."""
    named = waiting()
    named.assert_ignored(named.id_drawn(), "id_drawn")
    idle = Run(RMF_ROS2)
    idle.assert_ignored(idle.id_drawn(), "id_drawn")
