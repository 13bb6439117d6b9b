"""The answers a server keeps for the result requests that come after them (R21.4, R21.5)."""

from __future__ import annotations

import pytest

from dynevent.server.answers import ANSWER_RETENTION, KeptAnswers
from dynevent.server.outputs import AnswerGoal
from dynevent.wire.messages import Result
from dynevent.wire.vocab import Failure, GoalStatus


def _answer(uuid: str, status: GoalStatus = GoalStatus.SUCCEEDED, failure: str = "") -> AnswerGoal:
    return AnswerGoal(goal_uuid=uuid, status=status, result=Result(execution_failure=failure))


@pytest.mark.spec("R21.4", "R21.5")
def test_each_goals_first_answer_is_kept_for_fifteen_minutes() -> None:
    assert ANSWER_RETENTION == 15 * 60
    kept = KeptAnswers()
    first = _answer("1" * 32)
    kept.keep(first, now=100.0)
    kept.keep(_answer("1" * 32, GoalStatus.ABORTED, Failure.RESTART.value), now=101.0)
    assert kept.get("1" * 32, now=100.0 + ANSWER_RETENTION - 0.001) == first  # the first wins
    assert kept.get("2" * 32, now=101.0) is None
    assert kept.get("1" * 32, now=100.0 + ANSWER_RETENTION) is None  # past its time: unknown
    assert len(kept) == 0


@pytest.mark.spec("R21.4")
def test_a_restarts_answers_are_kept_from_the_restart_on() -> None:
    restart = _answer("3" * 32, GoalStatus.ABORTED, Failure.RESTART.value)
    kept = KeptAnswers({restart.goal_uuid: restart}, now=50.0, retention=10.0)
    assert kept.get(restart.goal_uuid, now=59.0) == restart
    assert kept.get(restart.goal_uuid, now=60.0) is None


def test_answers_past_their_time_are_forgotten_as_new_ones_come() -> None:
    """Memory stays that of the answers of the last retention period, however many goals came."""
    kept = KeptAnswers(retention=10.0)
    for second in range(1_000):
        kept.keep(_answer(f"{second:032x}"), now=float(second))
    assert len(kept) == 10
