"""A goal run as its caller follows it, whatever carries it: progress, one outcome, a bounded wait,
callbacks, and an await through the future the binding gives it."""

from __future__ import annotations

import asyncio
import threading

import pytest

from dynevent.client.outputs import Outcome, OutcomeKind, Progress
from dynevent.client.run import GoalRun
from dynevent.errors import GoalWaitTimeout, LocalError
from dynevent.wire.messages import Goal

OUTCOME = Outcome(
    goal_uuid="ab" * 16, goal=Goal(dynamic_event_seq=1, event_type=1, category="x"),
    kind=OutcomeKind.COMPLETED, id=3, status="completed", text="the event completed",
)  # fmt: skip


def test_a_run_reports_progress_then_ends_once_for_waiters_and_callbacks() -> None:
    seen: list[Progress] = []
    run = GoalRun(seen.append)
    with pytest.raises(GoalWaitTimeout, match=r"still open after 0\.01 s"):
        run.wait(0.01)
    early: list[object] = []
    run.add_done_callback(early.append)
    progress = Progress(goal_uuid="ab" * 16, id=3, status="underway", logs=())
    run.report(progress)
    assert run.progress == seen == [progress] and not run.done()
    threading.Timer(0.05, run.end, (OUTCOME,)).start()
    assert run.wait(5.0) is OUTCOME and run.done() and early == [OUTCOME]
    late: list[object] = []
    run.add_done_callback(late.append)  # over already: called at once, on the caller's thread
    assert late == [OUTCOME]


def test_a_run_is_awaited_through_its_future_and_says_so_without_one() -> None:
    async def main() -> object:
        future: asyncio.Future[object] = asyncio.get_running_loop().create_future()
        run = GoalRun(future=future)
        asyncio.get_running_loop().call_later(0.01, run.end, OUTCOME)
        return await run

    assert asyncio.run(main()) is OUTCOME
    with pytest.raises(LocalError, match="no future to await"):
        GoalRun().__await__()
