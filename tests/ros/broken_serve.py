"""``dynevent serve`` with one deliberate defect, for the probe to catch (tests/ros/test_ros_probe.py).

``python broken_serve.py DEFECT SERVE-ARGS...``: each defect is a small change to the real server
(:class:`dynevent.ros.server.DynamicEventServer` and the machine it runs), made in this process only.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

import attrs
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from dynevent.ros import server as ros_server
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.tools.cli import main
from dynevent.wire.vocab import DynamicState, EventType, GoalStatus, RejectReason, Tier


def _accept_despite(reason: RejectReason, only: EventType | None = None) -> None:
    """The request check (``accept``, and the steps of a goal's request and submission, which share
    it) lets through what it should refuse for ``reason`` (for goals of event type ``only``, when
    given: a server that branches on the event type before it checks)."""
    original = machine._decide

    def decide(state: Any, goal: Any, config: Any) -> Any:
        decision, parsed = original(state, goal, config)
        if (
            isinstance(decision, outs.Rejected)
            and decision.reason is reason
            and (only is None or goal.event_type == only)
        ):
            return outs.Accepted(event_type=goal.event_type), parsed
        return decision, parsed

    machine._decide = decide


def _volatile_topics() -> None:
    """The status and begin topics are published volatile, not transient-local (R1.4): a late
    subscriber gets nothing, and one that asks for transient-local (as R1.4 has clients do) never
    matches them."""

    def volatile(depth: int) -> QoSProfile:
        return QoSProfile(
            history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.VOLATILE,
        )  # fmt: skip

    ros_server.latched = volatile


def _rewrite(change: Callable[[Any, outs.Output], outs.Output | None]) -> None:
    """Each output goes through ``change`` before the server carries it out (None: dropped)."""
    original = ros_server.DynamicEventServer._carry_out

    def carry_out(self: Any, output: outs.Output) -> None:
        changed = change(self, output)
        if changed is not None:
            original(self, changed)

    ros_server.DynamicEventServer._carry_out = carry_out  # type: ignore[method-assign]


def _event_type(server: Any, uuid: str) -> int | None:
    handle = server._handles.get(uuid)
    return None if handle is None else int(handle.request.event_type)


def never_answers_cancel(server: Any, output: outs.Output) -> outs.Output | None:
    if isinstance(output, outs.AnswerGoal) and _event_type(server, output.goal_uuid) == EventType.CANCEL:
        return None
    return output


def hangs_next(server: Any, output: outs.Output) -> outs.Output | None:
    """A NEXT whose child completed is never answered."""
    if (
        isinstance(output, outs.AnswerGoal)
        and output.status is GoalStatus.SUCCEEDED
        and _event_type(server, output.goal_uuid) == EventType.NEXT
    ):
        return None
    return output


def running_after_child(server: Any, output: outs.Output) -> outs.Output | None:
    """After a child ends, the status says RUNNING (in standard mode, where it must say WAITING)."""
    if isinstance(output, outs.StartChild):
        server._broken_ran = True
    elif isinstance(output, outs.PublishBegin):
        server._broken_ran = False
    elif (
        isinstance(output, outs.PublishStatus)
        and getattr(server, "_broken_ran", False)
        and output.message.dynamic_state == DynamicState.WAITING
    ):
        message = attrs.evolve(output.message, dynamic_state=DynamicState.RUNNING, status="completed")
        return attrs.evolve(output, message=message)
    return output


def wrong_feedback_id(server: Any, output: outs.Output) -> outs.Output | None:
    if isinstance(output, outs.PublishFeedback):
        return attrs.evolve(output, feedback=attrs.evolve(output.feedback, id=output.feedback.id + 1))
    return output


def ignores_finished(server: Any, output: outs.Output) -> outs.Output | None:
    """FINISHED is answered, but the status never says the run ended."""
    if isinstance(output, outs.PublishStatus) and output.message.dynamic_state == DynamicState.INACTIVE:
        return None
    return output


def ignores_clamp(server: Any, output: outs.Output) -> outs.Output | None:
    """A stubborn period below the minimum is clamped without the warning (the start feedback's)."""
    if isinstance(output, outs.PublishFeedback) and output.feedback.logs:
        logs = tuple(entry for entry in output.feedback.logs if entry.tier != Tier.WARNING.value)
        return attrs.evolve(output, feedback=attrs.evolve(output.feedback, logs=logs))
    return output


def _skips_seq() -> None:
    """Each run's seq is the last one's plus 2 (runs 1, 3, 5): no case looks at the step between runs,
    the judge over the probe's exchange does (R3.1)."""
    machine.next_seq = lambda seq: (seq + 2) % 2**32


DEFECTS: dict[str, Callable[[], None]] = {
    "skips_seq": _skips_seq,
    "accepts_stale_seq": lambda: _accept_despite(RejectReason.SEQ_MISMATCH),
    "accepts_stale_next": lambda: _accept_despite(RejectReason.SEQ_MISMATCH, EventType.NEXT),
    "accepts_stale_cancel": lambda: _accept_despite(RejectReason.SEQ_MISMATCH, EventType.CANCEL),
    "accepts_cancel_after_the_run": lambda: _accept_despite(RejectReason.INACTIVE, EventType.CANCEL),
    "volatile_status": _volatile_topics,
    "accepts_unknown_category": lambda: _accept_despite(RejectReason.UNSUPPORTED_CATEGORY),
    "accepts_when_busy": lambda: _accept_despite(RejectReason.BUSY),
    "never_answers_cancel": lambda: _rewrite(never_answers_cancel),
    "hangs_next": lambda: _rewrite(hangs_next),
    "running_after_child": lambda: _rewrite(running_after_child),
    "wrong_feedback_id": lambda: _rewrite(wrong_feedback_id),
    "ignores_finished": lambda: _rewrite(ignores_finished),
    "ignores_clamp": lambda: _rewrite(ignores_clamp),
}

if __name__ == "__main__":
    DEFECTS[sys.argv[1]]()
    sys.exit(main(["serve", *sys.argv[2:]]))
