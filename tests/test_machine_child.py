"""docs/spec.md sections 7 (child progress and logs) and 8 (child end)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.wire.vocab import GoalStatus, Status
from scenario import (
    ABORTED,
    ANY_TEXT,
    CANCELED,
    RUNNING,
    SUCCEEDED,
    T0,
    WAITING,
    answer,
    cancel_goal,
    entry,
    feedback,
    finished_goal,
    next_goal,
    running,
    s,
    status,
    u,
    waiting,
)

STATUSES = [status.value for status in Status]
EARLY_END = ["canceled", "killed", "skipped"]


# --------------------------------------------------------------------------- R7.1, R7.4


@pytest.mark.spec("R7.1", "R7.4", "R2.3")
@pytest.mark.parametrize("reported", STATUSES)
def test_every_report_is_fed_back_and_mirrored(reported: str) -> None:
    run = running(child_id=5)
    expected: tuple[object, ...] = (feedback(u(1), reported, 5),)
    if reported != "underway":
        expected += (status(1, RUNNING, reported, 5),)
    assert run.progress(reported) == expected
    assert run.state.status == reported
    assert run.state.running is not None
    assert run.state.running.child_status == reported
    assert run.phase is RUNNING


@pytest.mark.spec("R7.1")
def test_reports_follow_the_child_of_the_current_goal() -> None:
    run = running(child_id=5, uuid=u(1))
    run.child_end("completed")
    run.submit(u(2), next_goal(1, 8))
    assert run.progress("delayed") == (feedback(u(2), "delayed", 8), status(1, RUNNING, "delayed", 8))


@pytest.mark.spec("R7.4", "R13.1")
@pytest.mark.parametrize("signal", ["canceled", "killed"])
def test_status_stays_canceled_or_killed_after_a_task_signal(signal: str) -> None:
    run = running(child_id=5)
    if signal == "canceled":
        run.task_cancel()
    else:
        run.task_kill()
    log_seq = run.state.log_seq
    assert run.progress("delayed", log="slowing down") == (
        outs.Log(entry=entry(log_seq, "info", T0, "slowing down")),
        feedback(u(1), "delayed", 5, entry(log_seq, "info", T0, "slowing down")),
    )
    assert run.state.status == signal


# --------------------------------------------------------------------------- R7.2


@pytest.mark.spec("R7.2", "R7.1")
@pytest.mark.parametrize("tier", ["uninitialized", "info", "warning", "error"])
def test_a_report_with_a_log_line(tier: str) -> None:
    run = running(child_id=5).at(s(200) + 1_999_999)
    log = entry(0, tier, s(200) + 1_999_999, "door 3 is closed")
    assert log.unix_millis_time == 200_001
    assert run.progress("blocked", log="door 3 is closed", tier=tier) == (
        outs.Log(entry=log),
        feedback(u(1), "blocked", 5, log),
        status(1, RUNNING, "blocked", 5, s(200) + 1_999_999),
    )
    assert run.state.log_seq == 1


@pytest.mark.spec("R7.2")
@given(now=st.integers(ins.NOW_RANGE[0], ins.NOW_RANGE[1]))
def test_log_time_is_the_floor_of_now_in_milliseconds(now: int) -> None:
    run = running(child_id=5)
    outputs = run.progress("underway", log="x", now=now)
    assert outputs[0] == outs.Log(entry=entry(0, "info", now, "x"))
    assert outputs[0].entry.unix_millis_time == now // 1_000_000
    assert (
        outputs[0].entry.unix_millis_time * 1_000_000
        <= now
        < (outputs[0].entry.unix_millis_time + 1) * 1_000_000
    )


@pytest.mark.spec("R7.2")
def test_log_time_before_1970_rounds_down() -> None:
    run = running(child_id=5)
    assert run.progress("underway", log="x", now=-1)[0] == outs.Log(entry=entry(0, "info", -1, "x"))
    assert run.progress("underway", log="x", now=-1)[0].entry.unix_millis_time == -1


@pytest.mark.spec("R7.2")
def test_an_empty_log_line_is_still_a_log_entry() -> None:
    run = running(child_id=5)
    assert run.progress("underway", log="") == (
        outs.Log(entry=entry(0, "info", T0, "")),
        feedback(u(1), "underway", 5, entry(0, "info", T0, "")),
    )


# --------------------------------------------------------------------------- R7.3


@pytest.mark.spec("R7.3")
def test_log_seq_wraps_at_2_32() -> None:
    run = running(child_id=5).evolve(log_seq=2**32 - 1)
    assert run.progress("underway", log="last")[0] == outs.Log(entry=entry(2**32 - 1, "info", T0, "last"))
    assert run.state.log_seq == 0
    assert run.progress("underway", log="first")[0] == outs.Log(entry=entry(0, "info", T0, "first"))
    assert run.state.log_seq == 1


@pytest.mark.spec("R7.3", "R12.2", "R13.1")
def test_log_seq_belongs_to_the_robot() -> None:
    run = waiting(event_id=1)
    run.submit(u(1), next_goal(1, 5))
    assert run.progress("underway", log="a")[0] == outs.Log(entry=entry(0, "info", T0, "a"))
    run.child_end("completed")
    # the clamp warning of the next goal takes the next seq, and its feedback carries it
    outputs = run.submit(u(2), next_goal(1, 6, stubborn=1.0))
    assert outputs[2] == outs.Log(entry=entry(1, "warning", T0, ANY_TEXT))
    assert outputs[4] == feedback(u(2), "underway", 6, entry(1, "warning", T0, ANY_TEXT))
    # the task signal's entry takes the next one
    assert run.task_cancel()[0] == outs.Log(entry=entry(2, "info", T0, "Received signal to cancel"))
    run.child_end("canceled")
    # a new run does not restart the count
    run.begin(event_id=7)
    run.submit(u(3), next_goal(2, 8))
    assert run.progress("underway", log="b")[0] == outs.Log(entry=entry(3, "info", T0, "b"))
    assert run.state.log_seq == 4


@pytest.mark.spec("R7.3")
def test_reports_without_a_log_line_take_no_seq() -> None:
    run = running(child_id=5)
    run.progress("delayed")
    run.progress("underway")
    assert run.state.log_seq == 0


# --------------------------------------------------------------------------- R8.1, R8.2, R8.4


@pytest.mark.spec("R8.1", "R8.2", "R8.4")
@pytest.mark.parametrize("final", STATUSES)
def test_child_end_answers_the_goal(final: str) -> None:
    run = running(child_id=5).at(s(300))
    goal_status = ABORTED if final in EARLY_END else SUCCEEDED
    assert run.child_end(final) == (
        answer(u(1), goal_status, "", final, 5),
        status(1, WAITING, "standby", 5, s(300)),
    )
    assert run.state.running is None
    assert run.state.status == "standby"
    assert run.state.stubborn is None
    assert run.phase is WAITING


@pytest.mark.spec("R8.2", "R10.3")
@pytest.mark.parametrize("final", STATUSES)
def test_child_end_after_an_action_level_cancel(final: str) -> None:
    run = running(child_id=5)
    run.cancel(u(1))
    goal_status = CANCELED if final in EARLY_END else SUCCEEDED
    assert run.child_end(final) == (
        answer(u(1), goal_status, "", final, 5),
        status(1, WAITING, "standby", 5),
    )


@pytest.mark.spec("R8.4")
def test_after_the_child_the_run_goes_on() -> None:
    run = running(child_id=5)
    run.child_end("failed")
    assert run.request(u(2), next_goal(1, 6)) == (outs.GoalAccepted(goal_uuid=u(2)),)
    assert run.start(u(2))[-1] == status(1, RUNNING, "underway", 6)
    run.child_end("completed")
    assert run.submit(u(3), finished_goal(1))[1] == answer(u(3), SUCCEEDED, "", "completed", 1)


@pytest.mark.spec("R8.4", "R12.1")
def test_child_end_begins_stubbornness_when_asked() -> None:
    run = running(child_id=5, stubborn=2.5)
    run.tick("L2", 3.0, -4.0)
    assert run.child_end("completed", now=s(400)) == (
        answer(u(1), SUCCEEDED, "", "completed", 5),
        outs.StubbornBegin(period=2.5, since=s(400), map_name="L2", x=3.0, y=-4.0),
        status(1, WAITING, "standby", 5, s(400)),
    )


# --------------------------------------------------------------------------- R8.3


@pytest.mark.spec("R8.3", "R8.2", "R9.3")
def test_waiting_cancels_succeed_in_start_order() -> None:
    run = running(child_id=5)
    run.request(u(3), cancel_goal(1, 5))
    run.request(u(2), cancel_goal(1, 5))
    run.start(u(2))
    run.start(u(3))
    assert run.state.cancels == (u(2), u(3))
    assert run.child_end("canceled") == (
        answer(u(1), ABORTED, "", "canceled", 5),
        answer(u(2), SUCCEEDED, "", "canceled", 5),
        answer(u(3), SUCCEEDED, "", "canceled", 5),
        status(1, WAITING, "standby", 5),
    )
    assert not run.state.cancels


@pytest.mark.spec("R8.3", "R8.2")
def test_a_cancel_that_came_too_late_shares_the_completed_result() -> None:
    run = running(child_id=5)
    run.submit(u(2), cancel_goal(1, 5))
    assert run.child_end("completed") == (
        answer(u(1), SUCCEEDED, "", "completed", 5),
        answer(u(2), SUCCEEDED, "", "completed", 5),
        status(1, WAITING, "standby", 5),
    )


@pytest.mark.spec("R8.3", "R8.2", "R10.3")
def test_cancel_goal_and_action_level_cancel_together() -> None:
    run = running(child_id=5)
    run.submit(u(2), cancel_goal(1, 5))
    run.cancel(u(1))
    assert run.child_end("killed") == (
        answer(u(1), GoalStatus.CANCELED, "", "killed", 5),
        answer(u(2), SUCCEEDED, "", "killed", 5),
        status(1, WAITING, "standby", 5),
    )
