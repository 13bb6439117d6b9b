"""Stopping a command line: SIGINT (Ctrl-C) and SIGTERM become one exception in the main thread.

Every command that holds something to close (a driver process, a ROS context, a recording) runs
its work inside :func:`interruptible`, closes what it holds as the exception passes, says what it
stopped, and exits 128 + the signal's number.  It takes SIGINT whatever the process inherited: a
shell starts a background job with SIGINT ignored, and Python then leaves Ctrl-C without effect.
"""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator

__all__ = ["Interrupted", "interruptible"]


class Interrupted(Exception):
    """Ctrl-C or SIGTERM, raised in the main thread inside :func:`interruptible`."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signal = signum

    @property
    def name(self) -> str:
        """``SIGINT`` or ``SIGTERM``."""
        return signal.Signals(self.signal).name


@contextlib.contextmanager
def interruptible() -> Iterator[None]:
    """SIGINT and SIGTERM raise :class:`Interrupted` in the main thread within the block (in place of
    Python's and rclpy's handlers, or of a SIGINT ignored since the process began, as a shell's
    background job's is; rclpy's shut the context down under whatever waits on it), the previous handlers
    restored after it.  A command line says what it stopped and exits 128 + the signal."""

    def interrupt(signum: int, frame: object) -> None:
        raise Interrupted(signum)

    previous = {signum: signal.signal(signum, interrupt) for signum in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
