"""A client's watch on the server processes its goals went to (R21.4), whatever carries it.

A server that restarts takes the pending result requests of its goals with it.  While goals are
open the binding tells the watch which server processes it sees (the GIDs of the robot's status
publishers: one per process) whenever they may have changed; once a new one has appeared, every
goal sent before it is an *orphan*, and the client asks again for its result, once every
:data:`ASK_AGAIN_PERIOD` seconds until it is answered: a server that kept the answer gives it, one
that does not know the goal ends it (``goal lost in a server restart``).  Times are the binding's
monotonic seconds.
"""

from __future__ import annotations

from collections.abc import Set

__all__ = ["ASK_AGAIN_PERIOD", "RestartWatch"]

#: How often the client asks again for the results of goals a restarted server took, in seconds.
ASK_AGAIN_PERIOD = 1.0


class RestartWatch:
    """The server processes last seen while goals are open, and the goals a newer one may have lost.
    Not thread-safe: the binding calls it under its own lock."""

    def __init__(self) -> None:
        self.servers: frozenset[bytes] | None = None  # None: not looked at since the last goal ended
        self.orphans: set[str] = set()
        self.ask_again_at = 0.0

    @property
    def looking(self) -> bool:
        """The processes are not known: the binding looks at the graph before the next goal goes."""
        return self.servers is None

    def sending(self, servers: frozenset[bytes] | None) -> None:
        """A goal is being sent to ``servers``, the processes the binding saw if it looked
        (:attr:`looking`); None when it did not."""
        if self.servers is None and servers is not None:
            self.servers = servers

    def seen(self, servers: frozenset[bytes], open_goals: Set[str], now: float) -> list[str]:
        """The processes seen now, with these goals open: the orphans whose results are due to be
        asked for again (then call :meth:`asked`), sorted."""
        if self.servers is not None and servers - self.servers:
            self.orphans |= open_goals  # sent before the new server process appeared
            self.ask_again_at = 0.0
        self.servers = servers
        self.orphans &= open_goals
        return sorted(self.orphans) if self.orphans and now >= self.ask_again_at else []

    def asked(self, now: float) -> None:
        """The results due were asked for again: the next time is one period on."""
        self.ask_again_at = now + ASK_AGAIN_PERIOD

    def answered(self, goal_uuid: str) -> None:
        """The goal's result came."""
        self.orphans.discard(goal_uuid)

    def idle(self) -> None:
        """No goal is open: the next goal's send looks at the processes again."""
        self.servers = None

    def wait(self, now: float) -> float | None:
        """Seconds until results are next due to be asked for again, or None when none are."""
        return self.ask_again_at - now if self.orphans else None
