"""What the judge's findings on rmf_ros2 stand for: the divergences the deployed server showed.

Open-RMF's own fleet adapter, run in the lab and recorded (tests/data/rmf_ros2), showed each of
these findings of the judge :func:`~dynevent.conformance.judge.check_trace` as one of the
divergences docs/divergences.md records (its D-number), or as one of the judge's open items: what a
client's view of an exchange cannot settle (a response recorded after the statuses its acceptance
caused).  ``dynevent probe`` labels every finding of its own exchange by :func:`label`, and
tests/conformance/judge/test_rmf_ros2_recordings.py holds the labels to the recordings.
"""

from __future__ import annotations

import re

from dynevent.conformance.judge.replay import Difference
from dynevent.conformance.judge.trace import SKIPS_OR_LOST, Answer, Finding
from dynevent.server.machine import RaceLoss
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import DynamicState, EventType, Failure, GoalStatus, Status

__all__ = ["OPEN_ITEMS", "label", "label_difference"]

# the statuses of a child and of a goal the labels read
_CANCELED, _COMPLETED = Status.CANCELED.value, Status.COMPLETED.value
_ABORTED, _SUCCEEDED, _CANCELED_GOAL = (
    GoalStatus.ABORTED.value,
    GoalStatus.SUCCEEDED.value,
    GoalStatus.CANCELED.value,
)

#: Open items: findings that are check's own misreading of what a recording does not hold.
OPEN_ITEMS: frozenset[str] = frozenset(
    {
        # the bag holds the client's record of a goal's response, stamped when it arrived, after the
        # statuses the server published on accepting it: check reads those as a child no goal explains
        "response_seen_late",
        # a task cancel is visible only as its log line and the INACTIVE that follows: check keeps the
        # child running
        "task_signal_unseen",
        # a client records its CANCEL's request after sending it, and the server may act on it first:
        # check reads the child's end before the CANCEL, which then looks sent to an idle robot (the
        # replay pulls such a CANCEL ahead, dynevent.conformance.judge.replay.CLIENT_LAG)
        "cancel_seen_late",
        # the same for a FINISHED: check reads the run's INACTIVE, which the FINISHED caused, before the
        # FINISHED, which then looks sent to an ended run
        "finished_seen_late",
        # a client records an answer when it arrives: a CANCEL's answer aborted 'idle', given while no
        # child ran, is read after a later NEXT's child started, and looks as if it named another child
        "answer_seen_late",
        # a client records the feedback that reaches it: one lost on the way leaves its child's log
        # seqs skipping (R7.3), as a server that skips them does
        "feedback_lost",
        # a client that never heard a goal's response (read from its feedback or answer) may have lost
        # its answer on the way too: a goal never answered is then not known to be the server's fault
        "answer_lost",
    }
)


def label(finding: Finding) -> str:
    """The D-number (or open item, :data:`OPEN_ITEMS`) a finding of rmf_ros2's stands for: the
    divergence of docs/divergences.md the deployed server's recordings showed it as; ``?`` for one
    no recording showed.  Decided from the finding's rule, code and values (what it saw, what the
    machine owed, its detail: :class:`~dynevent.conformance.judge.trace.Finding`), never its words."""
    rule, code, detail = finding.rule, finding.code, finding.detail
    seen, owed = finding.seen, finding.owed
    if code == "log_seq" and detail == SKIPS_OR_LOST:
        return "feedback_lost"
    if code == "log_seq" and detail == "skips":  # heard whole: the server's skip, which no recording showed
        return "?"
    if code == "answer_missing" and detail == "response_unheard":
        return "answer_lost"
    # a goal accepted while a child runs: a FINISHED ends the run under the child (D30); a NEXT finds
    # the robot freed by a CANCEL before the child's end (D1)
    if code == "accepted_busy":
        return "D30" if isinstance(seen, Goal) and seen.event_type == EventType.FINISHED else "D1"
    if code in _BY_CODE:
        return _BY_CODE[code]
    if code == "status_mismatch" and isinstance(seen, DynamicEventStatus):
        return _status_label(seen, owed if isinstance(owed, DynamicEventStatus) else None, detail)
    if code in ("goal_status", "result") and isinstance(seen, Answer) and isinstance(owed, Answer):
        return _answer_label(rule, code, seen, owed)
    if rule == "R3.4" and code == "begin_while_active":
        return "task_signal_unseen"
    # the same refusal as D31's R10.3 where the judge still held the NEXT queued when its cancel came
    # (its start's records read after the cancel's): the cancel refused, the NEXT answered at its
    # child's end
    if rule in ("R10.3", "R10.1") and code == "cancel_response":
        return "D31"
    if code == "feedback_not_running" and detail == "event_ended":
        return "D30"
    # a CANCEL frees the robot before its child ends (D1): the next NEXT is accepted and its child
    # starts while check still holds the cancelled one running
    if code == "race_not_lost" and detail == RaceLoss.SLOT.value:
        return "D1"
    if code == "race_not_lost" and detail == RaceLoss.ID.value:
        return "D10"  # the adapter's own numbering made the NEXT's id stale while it waited
    # a FINISHED accepted after another FINISHED of its run was answered: the run had ended (R4.3), and
    # no record read late explains it
    finished = isinstance(seen, Goal) and seen.event_type == EventType.FINISHED
    if code == "accepted_inactive" and finished and detail != "run_ended":
        return "finished_seen_late"
    return "?"


#: The labels a finding's code alone decides.
_BY_CODE = {
    "log_seq": "D9",
    "child_id": "D10",
    "clamp_not_reported": "D11",
    "accepted_cancel_idle": "D8",
    "accepted_cancel_id_mismatch": "D8",
    "accepted_stale_id": "D10",
    "accepted_uninitialized_event_type": "D7",
    "accepted_unknown_event_type": "D7",
    # rmf_ros2 reads a NaN stubborn period as none (its `stubborn_period > 0.0` test fails): the NEXT runs
    "accepted_non_finite_stubborn_period": "D12",
}


def _status_label(seen: DynamicEventStatus, owed: DynamicEventStatus | None, detail: str) -> str:
    """The label of a status that is not the one the machine's state has (``owed``, where known)."""
    phase, held = seen.dynamic_state, owed is not None and owed.dynamic_state == DynamicState.RUNNING
    if phase == DynamicState.WAITING and seen.id == 0 and seen.status == Status.UNINITIALIZED.value:
        return "D26"
    if phase == DynamicState.WAITING and seen.status == _CANCELED:
        return "D28"  # a waiting robot's status is standby (R8.4), whatever the judge held running
    if phase == DynamicState.RUNNING and owed is not None and owed.dynamic_state == DynamicState.WAITING:
        return "response_seen_late"
    if phase == DynamicState.INACTIVE and owed is not None and owed.status == _CANCELED:
        return "task_signal_unseen"
    if detail == "answered" and seen.status == _COMPLETED:
        return "D2"  # the status still shows the child whose goal was answered
    if phase == DynamicState.INACTIVE and owed is not None and owed.status == _COMPLETED:
        return "D30"
    # a CANCEL frees the robot before its child ends (D1): the next child runs, or the robot says
    # WAITING, while check still holds the cancelled one running
    moved = owed is not None and (seen.dynamic_event_seq, seen.id) != (owed.dynamic_event_seq, owed.id)
    if held and phase == DynamicState.RUNNING and moved:
        return "D1"
    if held and phase == DynamicState.WAITING and seen.status == Status.STANDBY.value:
        return "D1"
    return "?"


def _answer_label(rule: str, code: str, seen: Answer, owed: Answer) -> str:
    """The label of a goal's answer that is not the one the machine owes (``owed``)."""
    if rule == "R10.1" and code == "goal_status":
        return "D31"
    # where the cancel's callback stopped the child at once: the NEXT answered aborted `canceled`
    # before the cancel's refusal was read (the EasyFullControl site)
    if (
        rule == "R8.2"
        and code == "goal_status"
        and _plain(seen) == (_ABORTED, _CANCELED)
        and _plain(owed) == (_CANCELED_GOAL, _CANCELED)
    ):
        return "D31"
    idle = seen.status == _ABORTED and _failure(seen) == Failure.IDLE_CANCEL.value
    owed_idle = _failure(owed) == Failure.IDLE_CANCEL.value
    if rule == "R9.1" and code == "goal_status" and _plain(seen) == (_SUCCEEDED, _CANCELED) and owed_idle:
        return "cancel_seen_late"  # the child's end read before the CANCEL, which then looked idle
    if rule == "R9.2" and code == "result" and idle and _failure(owed) == Failure.CANCEL_ID.value:
        return "answer_seen_late"
    if rule == "R8.3" and code == "goal_status" and idle:
        return "D1"  # the second of two CANCELs found the robot freed by the first, and idle
    if (
        rule == "R5.2"
        and code == "goal_status"
        and _plain(seen) == (_SUCCEEDED, _COMPLETED)
        and not seen.result.id
    ):
        return "finished_seen_late"  # a FINISHED's answer (id 0), the FINISHED read after the run ended
    return "?"


def _plain(answer: Answer) -> tuple[str, str] | None:
    """An answer without an execution failure: its goal status and its result's status."""
    return None if answer.result.execution_failure else (answer.status, answer.result.status)


def _failure(answer: Answer) -> str:
    """The first line of an answer's execution failure."""
    return answer.result.execution_failure.split("\n", 1)[0]


def label_difference(difference: Difference) -> tuple[str, ...]:
    """The D-numbers a difference between the deployed server and serve's rmf_ros2 mode, replayed
    through the same recording (:func:`dynevent.conformance.judge.replay.compare_recording`), stands for;
    ``("?",)`` for one no divergence explains."""
    recorded, replayed = " ".join(difference.recorded), " ".join(difference.replayed)
    found: list[str] = []
    if difference.channel == "statuses":
        if "WAITING uninitialized id=0" in recorded and _CANCELED not in recorded:
            found.append("D26")  # and the standby before it, where the recorder missed that one
        if "WAITING standby" in recorded and "RUNNING standby" in replayed:
            found.append("D1")  # a CANCEL frees the robot while its child winds down
        if "WAITING canceled" in recorded and "RUNNING canceled" in replayed:
            found.append("D28")  # mended (R17.4): no recording shows it any more
    if difference.channel == "feedback":
        if re.search(r"goal \d+: (completed|canceled) id=#\d+", recorded) and "id=#" not in replayed:
            found.append("D32")  # mended (R17.7): no recording shows it any more
        if "logs warning" in replayed and "logs warning" not in recorded:
            found.append("D11")
    if difference.channel == "answers" and "failed to begin" in recorded and _CANCELED in replayed:
        found.append("D1")  # the second CANCEL found the robot freed by the first, and idle
    return tuple(found) or ("?",)
