"""§7. Child progress and logs: the tests of the rules of docs/spec.md §7.

The section's conformance vectors are src/dynevent/conformance/vectors/07-progress.json.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.holder import Execution
from support.scenario import (
    ANY_TEXT,
    CHILD_STATUSES,
    RUNNING,
    T0,
    entry,
    feedback,
    next_goal,
    running,
    running_server,
    s,
    status,
    u,
    waiting,
)

# --------------------------------------------------------------------------- R7.1


@pytest.mark.spec("R7.1", "R7.4", "R2.3")
@pytest.mark.parametrize("reported", CHILD_STATUSES)
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


@pytest.mark.spec("R7.1", "R7.2", "R7.4")
@pytest.mark.parametrize(
    ("method", "reported", "tier"),
    [
        (Execution.underway, "underway", "info"),
        (Execution.delayed, "delayed", "warning"),
        (Execution.blocked, "blocked", "warning"),
        (Execution.error, "error", "error"),
    ],
)
def test_execution_reports_with_their_tiers(
    method: Callable[..., tuple[object, ...]], reported: str, tier: str
) -> None:
    server = running_server()
    execution = Execution(server, 5)
    log = entry(0, tier, T0, "note")
    expected: tuple[object, ...] = (outs.Log(entry=log), feedback(u(1), reported, 5, log))
    if reported != "underway":
        expected += (status(1, RUNNING, reported, 5),)
    assert method(execution, "note", now=T0) == expected
    assert method(execution, now=T0) == (feedback(u(1), reported, 5),)
    assert execution.okay()


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
def test_the_one_reading_of_log_seqs_on_the_wire() -> None:
    """R7.3 as every reader of entries reads it (machine.log_seq_fault: the judge, the probe, the
    model): one up after an entry of the same started child; after any other, forward in uint32
    serial order, by any step (entries made while no child runs are on no feedback)."""
    fault = machine.log_seq_fault
    assert fault(None, 7, same_child=True) == ""  # the first entry seen
    assert fault(7, 8, same_child=True) == fault(2**32 - 1, 0, same_child=True) == ""
    assert fault(7, 9, same_child=True) == "skips"
    assert fault(7, 9, same_child=False) == fault(7, 7 + 2**31 - 1, same_child=False) == ""
    assert fault(7, 7, same_child=False) == "repeats"
    assert fault(7, 6, same_child=False) == fault(7, 7 + 2**31, same_child=False) == "backwards"
    assert machine.next_log_seq(2**32 - 1) == 0


@pytest.mark.spec("R7.3")
def test_reports_without_a_log_line_take_no_seq() -> None:
    run = running(child_id=5)
    run.progress("delayed")
    run.progress("underway")
    assert run.state.log_seq == 0


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


# --------------------------------------------------------------------------- R7.4


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
