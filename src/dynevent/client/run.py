"""One goal a client sent, as its caller follows it, whatever carries it: its progress as it comes,
then its one outcome, waited for with a bound from any thread, called back, or awaited.

The binding reports through the run (:meth:`GoalRun.report`, :meth:`GoalRun.end`) from its own
threads.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable
from typing import Any

from dynevent.client import outputs as cl
from dynevent.errors import GoalWaitTimeout, LocalError

__all__ = ["GoalRun", "loop_future", "on_loop"]


class GoalRun:
    """One goal of a client (the ROS binding's :class:`dynevent.ros.client.DynamicEventClient`): its
    progress, then its one outcome.  ``future`` (an awaitable with ``set_result``) makes it awaitable
    in the executor that completes it.

    ``result`` is the :class:`~dynevent.client.Outcome` once the goal is
    over, or the :class:`~dynevent.client.Refused` of a goal never sent.
    ``progress`` holds every :class:`~dynevent.client.Progress` so far.
    ``why_open``, when given, says why a goal may still be open (the binding's contact with the
    server, R21.5), for the message of a wait that ends at its bound.
    """

    def __init__(
        self,
        on_progress: Callable[[cl.Progress], None] | None = None,
        future: Any = None,
        why_open: Callable[[], str | None] | None = None,
    ) -> None:
        self.goal_uuid: str | None = None
        self.progress: list[cl.Progress] = []
        self.result: cl.Outcome | cl.Refused | None = None
        self._on_progress = on_progress
        self._over = threading.Event()
        self._future = future
        self._why_open = why_open
        self._callbacks: list[Callable[[cl.Outcome | cl.Refused], None]] = []
        self._callbacks_lock = threading.Lock()

    def done(self) -> bool:
        """The goal is over (or was never sent)."""
        return self._over.is_set()

    def wait(self, timeout: float) -> cl.Outcome | cl.Refused:
        """Block until the goal is over, at most ``timeout`` seconds (another thread spins the node)."""
        if not self._over.wait(timeout):
            why = None if self._why_open is None else self._why_open()
            raise GoalWaitTimeout(
                f"goal {self.goal_uuid} still open after {timeout:g} s" + ("" if why is None else f": {why}")
            )
        assert self.result is not None
        return self.result

    def __await__(self) -> Any:
        """Await the outcome inside the executor that completes ``future`` (rclpy's, for the ROS
        binding's client)."""
        if self._future is None:
            raise LocalError("this goal run has no future to await: wait() for it, or add_done_callback")
        return self._future.__await__()

    def report(self, progress: cl.Progress) -> None:
        """The binding's: the goal made ``progress`` (kept, and handed to ``on_progress``)."""
        self.progress.append(progress)
        if self._on_progress is not None:
            self._on_progress(progress)

    def add_done_callback(self, callback: Callable[[cl.Outcome | cl.Refused], None]) -> None:
        """Call ``callback`` with the result when the goal is over (at once when it is): on the
        executor's thread, or on the caller's when the goal is already over."""
        with self._callbacks_lock:
            if self.result is None:
                self._callbacks.append(callback)
                return
            result = self.result
        callback(result)

    def end(self, result: cl.Outcome | cl.Refused) -> None:
        """The binding's: the goal is over with ``result`` (waiters woken, callbacks called)."""
        with self._callbacks_lock:
            self.result = result
            callbacks, self._callbacks = self._callbacks, []
        self._over.set()
        if self._future is not None:
            self._future.set_result(result)
        for callback in callbacks:
            callback(result)


def loop_future(loop: asyncio.AbstractEventLoop, run: GoalRun) -> asyncio.Future[cl.Outcome | cl.Refused]:
    """A future of ``loop`` that gets ``run``'s result, handed over to the loop's thread from whichever
    thread ends the run (an asyncio caller's view of a goal)."""
    future: asyncio.Future[cl.Outcome | cl.Refused] = loop.create_future()

    def done(result: cl.Outcome | cl.Refused) -> None:
        if not future.done():  # (a caller may have cancelled its future)
            future.set_result(result)

    def hand_over(result: cl.Outcome | cl.Refused) -> None:
        loop.call_soon_threadsafe(done, result)

    run.add_done_callback(hand_over)
    return future


def on_loop(
    loop: asyncio.AbstractEventLoop, callback: Callable[[cl.Progress], None] | None
) -> Callable[[cl.Progress], None] | None:
    """``callback``, called on ``loop``'s thread with each progress report, whichever thread reports."""
    if callback is None:
        return None
    report = callback

    def hand_over(progress: cl.Progress) -> None:
        loop.call_soon_threadsafe(report, progress)

    return hand_over
