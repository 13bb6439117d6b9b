"""The answers a server keeps for result requests that come after them (R21.4, R21.5).

A client asks for a goal's result when it sends the goal, and again when it could not hear the
answer: after a restart of the server (R21.4), or after the network cut it off for longer than the
middleware's lease (R21.5).  A server answers such a request from what it kept: each goal's first
answer, for :data:`ANSWER_RETENTION` seconds after it was given.  rclpy's action server alone keeps a
result only 10 s (its ``result_timeout`` since rclpy 7), and answers a request after that with
``STATUS_UNKNOWN``, which a client must read as a goal the server never took.

The binding holds one :class:`KeptAnswers` per robot, gives it every answer as it is given, and asks
it for a goal its action server no longer knows.  Times are the binding's monotonic seconds.
"""

from __future__ import annotations

import collections
import threading
from collections.abc import Mapping

from dynevent.server.outputs import AnswerGoal

__all__ = ["ANSWER_RETENTION", "KeptAnswers"]

#: How long a goal's answer is kept for its client, in seconds: 15 minutes, rcl's (and rclcpp's)
#: ``result_timeout``, whatever the action server under the binding keeps.
ANSWER_RETENTION = 900.0


class KeptAnswers:
    """Each goal's first answer, by goal UUID, for ``retention`` seconds after it was kept.

    ``answers`` are answers kept before this process (a restart's, from the store): kept from
    ``now`` on.  Every method may be called from any thread.
    """

    def __init__(
        self,
        answers: Mapping[str, AnswerGoal] | None = None,
        *,
        now: float = 0.0,
        retention: float = ANSWER_RETENTION,
    ) -> None:
        self.retention = retention
        self._lock = threading.Lock()
        # in the order kept, so that those past their time are the first ones
        self._kept: collections.OrderedDict[str, tuple[float, AnswerGoal]] = collections.OrderedDict(
            (uuid, (now, answer)) for uuid, answer in (answers or {}).items()
        )

    def __len__(self) -> int:
        with self._lock:
            return len(self._kept)

    def keep(self, answer: AnswerGoal, now: float) -> None:
        """Keep ``answer`` from ``now``, unless its goal has one already (the first answer wins)."""
        with self._lock:
            self._forget(now)
            if answer.goal_uuid not in self._kept:
                self._kept[answer.goal_uuid] = (now, answer)

    def get(self, goal_uuid: str, now: float) -> AnswerGoal | None:
        """The answer kept for ``goal_uuid``, or None when there is none, or no longer."""
        with self._lock:
            self._forget(now)
            kept = self._kept.get(goal_uuid)
        return None if kept is None else kept[1]

    def _forget(self, now: float) -> None:
        while self._kept:
            uuid, (kept_at, _answer) = next(iter(self._kept.items()))
            if now - kept_at < self.retention:
                return
            del self._kept[uuid]
