"""A goal run as its caller follows it, whatever carries it: progress, one outcome, a bounded wait,
callbacks, and an await through the future the binding gives it."""

from __future__ import annotations

import asyncio
import threading

import pytest

from dynevent.client.outputs import Outcome, OutcomeKind, Progress
from dynevent.client.run import GoalRun, loop_future, on_loop
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


def test_an_asyncio_caller_gets_progress_and_the_result_on_its_loops_thread() -> None:
    """A run reported and ended from another thread (the binding's executor): the loop's future gets
    the result, and each progress report reaches the callback on the loop's own thread."""
    progress = Progress(goal_uuid="ab" * 16, id=3, status="underway", logs=())
    threads: list[int] = []

    async def main() -> object:
        loop = asyncio.get_running_loop()
        report = on_loop(loop, lambda _: threads.append(threading.get_ident()))
        assert on_loop(loop, None) is None
        run = GoalRun(report)
        future = loop_future(loop, run)
        worker = threading.Thread(target=lambda: (run.report(progress), run.end(OUTCOME)))
        worker.start()
        result = await asyncio.wait_for(future, 5.0)
        worker.join()
        return result

    assert asyncio.run(main()) is OUTCOME
    assert threads == [threading.main_thread().ident]


def test_a_future_its_caller_cancelled_takes_no_result() -> None:
    errors: list[dict[str, object]] = []

    async def main() -> bool:
        loop = asyncio.get_running_loop()
        loop.set_exception_handler(lambda _, context: errors.append(context))
        run = GoalRun()
        future = loop_future(loop, run)
        future.cancel()
        run.end(OUTCOME)  # the hand-over finds the future done: nothing raised on the loop
        await asyncio.sleep(0.01)
        return future.cancelled()

    assert asyncio.run(main()) and errors == []
