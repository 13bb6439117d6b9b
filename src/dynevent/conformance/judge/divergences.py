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
from dynevent.conformance.judge.trace import Finding
from dynevent.wire.vocab import Status

__all__ = ["OPEN_ITEMS", "label", "label_difference"]

# the status texts the judge's sentences quote
_CANCELED, _COMPLETED = Status.CANCELED.value, Status.COMPLETED.value

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
        # check reads the status of the cancelled child's end before the CANCEL, as the child still
        # running (the replay pulls such a CANCEL ahead, dynevent.conformance.judge.replay.CLIENT_LAG)
        "cancel_seen_late",
        # the same for a FINISHED: check reads the run's INACTIVE, which the FINISHED caused, before the
        # FINISHED, which then looks sent to an ended run
        "finished_seen_late",
        # a client records an answer when it arrives: a CANCEL's answer aborted 'idle', given while no
        # child ran, is read after a later NEXT's child started, and looks as if it named another child
        "answer_seen_late",
    }
)


def label(finding: Finding) -> str:
    """The D-number (or open item, :data:`OPEN_ITEMS`) a finding of rmf_ros2's stands for: the
    divergence of docs/divergences.md the deployed server's recordings showed it as; ``?`` for one
    no recording showed."""
    rule, code, message, expected = finding.rule, finding.code, finding.message, finding.expected
    if code == "log_seq":
        return "D9"
    if code == "child_id":
        return "D10"
    if code == "clamp_not_reported":
        return "D11"
    if code == "status_mismatch" and re.search(r"status WAITING seq=\d+ id=0 uninitialized", message):
        return "D26"
    if code == "status_mismatch" and re.search(r"status WAITING seq=\d+ id=\d+ canceled", message):
        return "cancel_seen_late" if expected.startswith("RUNNING") else "D28"
    if code == "status_mismatch" and "status RUNNING" in message and expected.startswith("WAITING"):
        return "response_seen_late"
    if code == "status_mismatch" and "status INACTIVE" in message and _CANCELED in expected:
        return "task_signal_unseen"
    if rule == "R3.4" and code == "begin_while_active":
        return "task_signal_unseen"
    if code == "status_mismatch" and "still, after goal" in message and _COMPLETED in message:
        return "D2"
    if code in ("accepted_cancel_idle", "accepted_cancel_id_mismatch"):
        return "D8"
    if code == "accepted_stale_id":
        return "D10"
    if rule == "R10.3" and code == "cancel_response":
        return "D31"
    # the same refusal where the judge still held the NEXT queued when its cancel came (its start's
    # records read after the cancel's): the cancel refused, the NEXT answered at its child's end
    if rule == "R10.1" and code in ("cancel_response", "goal_status"):
        return "D31"
    # and where the cancel's callback stopped the child at once: the NEXT answered aborted `canceled`
    # before the cancel's refusal was read (the EasyFullControl site)
    if (
        rule == "R8.2"
        and code == "goal_status"
        and "answered aborted: canceled" in message
        and expected.startswith("canceled: canceled")
    ):
        return "D31"
    if code == "status_mismatch" and "status INACTIVE" in message and _COMPLETED in expected:
        return "D30"
    if code == "feedback_not_running" and "whose event has ended" in message:
        return "D30"
    # a CANCEL frees the robot before its child ends (D1): the next NEXT is accepted and its child
    # starts while check still holds the cancelled one running, and the robot says WAITING meanwhile
    if code == "accepted_busy" or (code == "race_not_lost" and "holds the running slot" in expected):
        return "D1"
    running = re.search(r"status RUNNING seq=(\d+) id=(\d+)", message)
    held = re.match(r"RUNNING seq=(\d+) id=(\d+)", expected)
    if code == "status_mismatch" and running and held and running.groups() != held.groups():
        return "D1"
    if code == "status_mismatch" and re.search(r"status WAITING seq=\d+ id=\d+ standby", message) and held:
        return "D1"
    if code == "race_not_lost" and "is no longer above" in expected:
        return "D10"  # the adapter's own numbering made the NEXT's id stale while it waited
    if rule == "R9.1" and code == "goal_status" and "succeeded: canceled" in message and "idle" in expected:
        return "cancel_seen_late"  # the child's end read before the CANCEL, which then looked idle
    if code in ("accepted_uninitialized_event_type", "accepted_unknown_event_type"):
        return "D7"
    idle = "aborted: 'an idle dynamic event cannot be cancelled'"
    if rule == "R9.2" and code == "result" and idle in message and "does not match" in expected:
        return "answer_seen_late"
    if rule == "R8.3" and code == "goal_status" and idle in message:
        return "D1"  # the second of two CANCELs found the robot freed by the first, and idle
    if code == "accepted_inactive" and message.startswith("FINISHED"):
        return "finished_seen_late"
    if rule == "R5.2" and code == "goal_status" and "succeeded: completed id=0" in message:
        return "finished_seen_late"  # a FINISHED's answer (id 0), the FINISHED read after the run ended
    return "?"


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
