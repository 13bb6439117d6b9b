"""§13. Task cancel and kill: the tests of the rules of docs/spec.md §13.

The section's conformance vectors are src/dynevent/conformance/vectors/13-task-signal.json.
"""

from __future__ import annotations

import pytest

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.holder import Execution
from support.scenario import (
    ABORTED,
    CANCELED,
    INACTIVE,
    RACE,
    RUNNING,
    SUCCEEDED,
    T0,
    aborted,
    answer,
    cancel_goal,
    deferred,
    entry,
    feedback,
    next_goal,
    running,
    running_server,
    status,
    stubborn,
    u,
    waiting,
)

CANCEL_TEXT = "Received signal to cancel"


KILL_TEXT = "Received signal to kill"


ENDED = status(1, INACTIVE, "uninitialized", 0)


def _log(seq: int, text: str) -> outs.Log:
    return outs.Log(entry=entry(seq, "info", T0, text))


# --------------------------------------------------------------------------- R13.1


@pytest.mark.spec("R13.1", "R13.2")
def test_task_cancel_with_a_started_child() -> None:
    run = running(child_id=5)
    assert run.task_cancel() == (
        _log(0, CANCEL_TEXT),
        feedback(u(1), "underway", 5, entry(0, "info", T0, CANCEL_TEXT)),
        outs.CancelChild(id=5),
        status(1, RUNNING, "canceled", 5),
    )
    state = run.state
    assert (state.task_signal, state.status, state.active, state.log_seq) == ("canceled", "canceled", True, 1)
    assert state.running is not None
    assert state.running.canceling
    assert not state.running.cancel_requested


@pytest.mark.spec("R13.1", "R13.2")
def test_task_kill_with_a_started_child_feeds_back_its_status() -> None:
    run = running(child_id=5)
    run.progress("delayed")
    assert run.task_kill() == (
        _log(0, KILL_TEXT),
        feedback(u(1), "delayed", 5, entry(0, "info", T0, KILL_TEXT)),
        outs.KillChild(id=5),
        status(1, RUNNING, "killed", 5),
    )
    assert (run.state.task_signal, run.state.status) == ("killed", "killed")


# --------------------------------------------------------------------------- R13.2


@pytest.mark.spec("R13.2", "R13.4")
def test_without_automatic_cancel_a_kill_ends_killed() -> None:
    server = running_server()
    execution = Execution(server, 5, automatic_cancel=False)
    server.step(ins.TaskKill(now=T0))
    assert execution.kill(now=T0) == ()
    assert execution.finished(now=T0) == (
        answer(u(1), ABORTED, "", "killed", 5),
        outs.DynamicEventFinished(status="killed"),
        status(1, INACTIVE, "uninitialized", 0),
    )


@pytest.mark.spec("R13.2", "R9.3", "R10.3")
@pytest.mark.parametrize("told", ["cancel_goal", "action_cancel"])
def test_task_cancel_does_not_tell_a_stopping_child_again(told: str) -> None:
    run = running(child_id=5)
    if told == "cancel_goal":
        run.submit(u(2), cancel_goal(1, 5))
    else:
        run.cancel(u(1))
    assert run.task_cancel() == (
        _log(0, CANCEL_TEXT),
        feedback(u(1), "underway", 5, entry(0, "info", T0, CANCEL_TEXT)),
        status(1, RUNNING, "canceled", 5),
    )


@pytest.mark.spec("R13.2", "R9.3")
def test_task_kill_always_kills_a_stopping_child() -> None:
    run = running(child_id=5)
    run.submit(u(2), cancel_goal(1, 5))
    assert run.task_kill()[2] == outs.KillChild(id=5)


# --------------------------------------------------------------------------- R13.3


@pytest.mark.spec("R13.3", "R13.1", "R11.2")
@pytest.mark.parametrize(("signal", "text"), [("canceled", CANCEL_TEXT), ("killed", KILL_TEXT)])
def test_task_signal_with_no_child_ends_at_once(signal: str, text: str) -> None:
    run = waiting(event_id=1)
    outputs = run.task_cancel() if signal == "canceled" else run.task_kill()
    assert outputs == (_log(0, text), outs.DynamicEventFinished(status=signal), ENDED)
    assert (run.state.active, run.state.status, run.state.task_signal, run.phase) == (
        False,
        signal,
        signal,
        INACTIVE,
    )


@pytest.mark.spec("R13.3", "R13.1", "R12.5")
def test_task_cancel_while_stubborn() -> None:
    run = stubborn(3.0)
    assert run.task_cancel() == (
        _log(0, CANCEL_TEXT),
        outs.StubbornEnd(),
        outs.DynamicEventFinished(status="canceled"),
        ENDED,
    )
    assert run.state.stubborn is None


@pytest.mark.spec("R13.3", "R8.2")
@pytest.mark.parametrize(("signal", "text"), [("canceled", CANCEL_TEXT), ("killed", KILL_TEXT)])
def test_task_signal_with_a_deferred_child(signal: str, text: str) -> None:
    run = deferred(child_id=5)
    outputs = run.task_cancel() if signal == "canceled" else run.task_kill()
    assert outputs == (
        _log(0, text),
        answer(u(1), ABORTED, "", signal, 5),
        outs.DynamicEventFinished(status=signal),
        ENDED,
    )
    assert (run.state.running, run.state.active) == (None, False)


@pytest.mark.spec("R13.3", "R13.1", "R12.5", "R8.2")
def test_task_kill_with_a_deferred_child_while_stubborn() -> None:
    run = stubborn(3.0, child_id=5)
    run.interrupt()
    run.submit(u(2), next_goal(1, 6))
    assert run.task_kill() == (
        _log(0, KILL_TEXT),
        outs.StubbornEnd(),
        answer(u(2), ABORTED, "", "killed", 6),
        outs.DynamicEventFinished(status="killed"),
        ENDED,
    )


@pytest.mark.spec("R13.3", "R11.2", "R5.2")
def test_queued_goals_outlive_a_task_cancel_and_lose_the_race() -> None:
    run = waiting()
    run.request(u(2), next_goal(1, 5))
    run.task_cancel()
    assert run.start(u(2)) == (outs.ExecuteGoal(goal_uuid=u(2)), aborted(u(2), RACE))


# --------------------------------------------------------------------------- R13.4


@pytest.mark.spec("R13.4", "R8.2", "R8.3")
def test_the_child_ends_after_a_task_cancel() -> None:
    run = running(child_id=5, stubborn=3.0)
    run.task_cancel()
    run.submit(u(2), cancel_goal(1, 5))
    assert run.child_end("canceled") == (
        answer(u(1), ABORTED, "", "canceled", 5),
        answer(u(2), SUCCEEDED, "", "canceled", 5),
        outs.DynamicEventFinished(status="canceled"),
        ENDED,
    )
    state = run.state
    assert (state.active, state.status, state.running, state.cancels, state.stubborn) == (
        False,
        "canceled",
        None,
        (),
        None,
    )


@pytest.mark.spec("R13.4", "R8.2")
def test_a_child_that_completes_anyway_still_ends_the_cancelled_event() -> None:
    run = running(child_id=5)
    run.task_cancel()
    assert run.child_end("completed") == (
        answer(u(1), SUCCEEDED, "", "completed", 5),
        outs.DynamicEventFinished(status="canceled"),
        ENDED,
    )


@pytest.mark.spec("R13.4", "R8.2", "R10.3")
def test_the_child_ends_after_a_task_kill_and_an_action_level_cancel() -> None:
    run = running(child_id=5)
    run.cancel(u(1))
    run.task_kill()
    assert run.child_end("killed") == (
        answer(u(1), CANCELED, "", "killed", 5),
        outs.DynamicEventFinished(status="killed"),
        ENDED,
    )


# --------------------------------------------------------------------------- R13.5


@pytest.mark.spec("R13.5", "R13.1", "R13.2")
def test_kill_after_cancel_escalates() -> None:
    run = running(child_id=5)
    run.task_cancel()
    assert run.task_kill() == (
        _log(1, KILL_TEXT),
        feedback(u(1), "underway", 5, entry(1, "info", T0, KILL_TEXT)),
        outs.KillChild(id=5),
        status(1, RUNNING, "killed", 5),
    )
    assert run.state.task_signal == "killed"
    assert run.child_end("killed") == (
        answer(u(1), ABORTED, "", "killed", 5),
        outs.DynamicEventFinished(status="killed"),
        ENDED,
    )


@pytest.mark.spec("R13.5", "R13.1", "R7.4")
def test_escalation_feeds_back_the_last_reported_child_status() -> None:
    run = running(child_id=5)
    run.task_cancel()
    run.progress("delayed")
    assert run.task_kill()[1] == feedback(u(1), "delayed", 5, entry(1, "info", T0, KILL_TEXT))
    assert run.state.status == "killed"


@pytest.mark.spec("R13.5", "R18.7")
@pytest.mark.parametrize(("first", "second"), [("cancel", "cancel"), ("kill", "kill"), ("kill", "cancel")])
def test_repeated_signals_are_ignored(first: str, second: str) -> None:
    run = running(child_id=5)
    run.task_cancel() if first == "cancel" else run.task_kill()
    outputs = run.task_cancel() if second == "cancel" else run.task_kill()
    run.assert_ignored(outputs, f"task_{second}")


# --------------------------------------------------------------------------- R13.6


@pytest.mark.spec("R13.6", "R18.6")
@pytest.mark.parametrize("signal", ["task_cancel", "task_kill"])
def test_a_task_signal_ends_the_interruption_with_the_task(signal: str) -> None:
    run = waiting()
    run.interrupt()
    getattr(run, signal)()
    assert run.phase is INACTIVE and not run.state.interrupted
    run.assert_ignored(run.resume(), "resume")


@pytest.mark.spec("R13.6", "R6.4")
def test_the_next_task_does_not_inherit_an_interruption() -> None:
    run = running(child_id=5)
    run.interrupt()
    run.task_kill()
    run.child_end("killed")
    assert run.phase is INACTIVE and not run.state.interrupted
    run.begin(event_id=20)
    outputs = run.submit(u(9), next_goal(2, 21))
    assert any(isinstance(output, outs.StartChild) for output in outputs)  # not deferred
