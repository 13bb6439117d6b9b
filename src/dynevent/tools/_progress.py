"""A progress line on a terminal for long commands; nothing at all when standard error is not one."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

__all__ = ["Progress"]


class Progress:
    """One line on ``stream`` (standard error), rewritten at most every ``interval`` seconds.

    It is shown only when ``stream`` is a terminal, so that piped and captured
    output never holds it, and it is erased by :meth:`close`, before the
    command prints its report.
    """

    def __init__(
        self, label: str, total: int | None = None, *, stream: TextIO | None = None, interval: float = 0.2
    ) -> None:
        self._label = label
        self._total = total
        self._stream = stream if stream is not None else sys.stderr
        self._interval = interval
        try:
            self.active = self._stream.isatty()
        except (AttributeError, ValueError):  # a closed or unusual stream: no progress
            self.active = False
        self._shown = False
        self._last = time.monotonic()  # the first line waits one interval: quick work shows nothing

    def update(self, done: int, detail: str = "") -> None:
        """Say that ``done`` units of ``total`` are done (``detail``: what they are)."""
        if self._due():
            amount = f"{min(100, 100 * done // self._total)}%" if self._total else f"{done:,}"
            self._show(f"{amount}{' ' + detail if detail else ''}")

    def show(self, text: str) -> None:
        """Show ``text`` after the label: what is going on, where there is no count."""
        if self._due():
            self._show(text)

    def above(self, say: Callable[[str], None]) -> Callable[[str], None]:
        """``say``, for the lines a command prints while its progress shows: the progress line is
        erased first (the next update draws it again), so that no printed line is written over it."""

        def said(line: str) -> None:
            self.close()
            say(line)

        return said

    def _due(self) -> bool:
        if not self.active:
            return False
        now = time.monotonic()
        if now - self._last < self._interval:
            return False
        self._last = now
        return True

    def _show(self, text: str) -> None:
        self._write(f"\r{self._label}: {text}\x1b[K")
        self._shown = True

    def close(self) -> None:
        """Erase the line, if one was shown."""
        if self._shown:
            self._write("\r\x1b[K")
            self._shown = False

    def _write(self, text: str) -> None:
        try:
            self._stream.write(text)
            self._stream.flush()
        except (OSError, ValueError):  # the terminal went away: the work goes on without progress
            self.active = False
