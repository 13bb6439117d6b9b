"""``dynevent send``: one goal to one robot, over the ROS binding's client, with its feedback and outcome.

It prints the robot's status as first seen, every feedback as it arrives,
and the typed outcome; for a goal the robot refused (a ROS refusal carries
no reason) it explains, from the status, why the robot most likely refused
it and what to send instead (:mod:`dynevent.conformance.explain`).  Everything is bounded
by ``--timeout``.  Exit status: 0 when the goal succeeded (a NEXT whose event
completed, a CANCEL or FINISHED that was carried out), 1 when it did not
(refused, failed, cancelled, aborted, timed out), 2 on bad usage or input, or
when no server or status was found within the timeout.
"""

from __future__ import annotations

import signal
import time
from collections.abc import Callable

import attrs

from dynevent import client as cl
from dynevent import descriptions
from dynevent.conformance import explain
from dynevent.conformance.judge.trace import TraceWriter
from dynevent.errors import (
    FileError,
    SendError,  # defined there with every error; importable here too
)
from dynevent.interrupts import Interrupted, interruptible
from dynevent.ros.client import DynamicEventClient, GoalRun, GoalWaitTimeout
from dynevent.ros.graph import graph_text, no_server_text, servers_seen
from dynevent.ros.spinning import Session
from dynevent.server import outputs as outs
from dynevent.tools.live import flush_output, offline, see_the_whole_graph
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.units import SECOND
from dynevent.wire.vocab import EventType, GoalStatus

__all__ = ["SendError", "SendOptions", "run"]


def _succeeded(event_type: EventType, outcome: cl.Outcome) -> bool:
    if outcome.goal_status is not GoalStatus.SUCCEEDED:
        return False
    return event_type != EventType.NEXT or outcome.kind is cl.OutcomeKind.COMPLETED


def _progress_line(progress: cl.Progress) -> list[str]:
    lines = [f"[id {progress.id}] {progress.status}"]
    lines.extend(f"[id {progress.id}]   {entry.tier}: {entry.text}" for entry in progress.logs)
    return lines


@attrs.frozen(kw_only=True)
class SendOptions:
    """What ``dynevent send`` is asked to do, its flags read and checked by the command line."""

    fleet: str
    robot: str
    event_type: EventType
    category: str = ""  # a NEXT's
    description: str = ""  # a NEXT's
    stubborn_period: float = 0.0  # a NEXT's, in seconds
    timeout: float = 60.0  # the bound on the whole exchange, in seconds
    trace: str | None = None  # a trace file of everything sent and received
    introspection: bool = False  # publish the action client's service events
    wait: bool = False  # wait for the robot's server up to the timeout, whatever other servers there are
    ros_args: tuple[str, ...] = ()  # ROS 2's own command-line arguments (``--ros-args ...``)


def run(args: SendOptions, say: Callable[[str], None]) -> int:
    """Send the goal; 0, 1 or 2 as the module docs say."""
    event_type, category, description = args.event_type, args.category, args.description
    timeout = float(args.timeout)
    started = time.monotonic()

    def left() -> float:
        return max(timeout - (time.monotonic() - started), 0.0)

    trace = _open_trace(args)
    see_the_whole_graph()
    offline(say)
    session = Session("dynevent_send", args.ros_args)
    node = session.node
    # a description of the field's categories is checked here as every server checks its shape
    # (R4.18): one the robot would refuse is refused here, with the server's errors, and never sent
    client = DynamicEventClient(
        node,
        args.fleet,
        args.robot,
        validators=descriptions.shape_validators(),
        trace=trace,
        on_contact=lambda change: say(_contact_line(f"{args.fleet}/{args.robot}", change)),
    )
    if args.introspection:
        client.introspect()
    session.start()
    try:
        try:
            with interruptible():
                if not _found(client, node, args, left, say):
                    return 2
                if not client.wait_for_status(left()):
                    say(f"no status from {args.fleet}/{args.robot} within {timeout:g} s")
                    return 2
        except Interrupted as stop:
            name = signal.Signals(stop.signal).name
            say(f"{name} while waiting for {args.fleet}/{args.robot}'s server and status: nothing was sent")
            return 128 + stop.signal
        status = _status(client)
        say(f"{args.fleet}/{args.robot}: {explain.status_text(status)}")

        def report(progress: cl.Progress) -> None:
            for line in _progress_line(progress):
                say(line)

        if event_type == EventType.NEXT:
            goal_run = client.next(
                category, description, stubborn_period=args.stubborn_period, on_progress=report
            )
        elif event_type == EventType.CANCEL:
            goal_run = client.cancel(on_progress=report)
        else:
            goal_run = client.finish()
        try:
            with interruptible():
                result = goal_run.wait(left())
        except GoalWaitTimeout:
            cut = client.contact_text()
            say(f"no answer within {timeout:g} s" + ("" if cut is None else f": {cut}"))
            return 1
        except Interrupted as stop:
            return _stop_goal(client, goal_run, event_type, stop.signal, say)
        if isinstance(result, cl.Refused):
            rejection = result.rejection
            say(f"not sent: the robot would refuse it: {rejection.reason.value}: {rejection.text}")
            return 1
        say(f"outcome: {result.kind.value}: {result.text}")
        if result.kind is cl.OutcomeKind.REJECTED:
            say(_why_refused(status, result.goal))
        return 0 if _succeeded(event_type, result) else 1
    finally:
        flush_output()  # what was printed reaches its reader, whatever the close-down does
        session.close(client.destroy)
        if trace is not None:
            trace.close()


#: How long, after Ctrl-C or SIGTERM, send waits for the goal it sent to be cancelled and answered.
STOP_BOUND = 10.0
#: How long send looks for the robot's server before it says which other servers the graph has.
LOOK = 3.0
#: How often send looks at the graph again while it waits for the robot's server.
WAKE = 0.5
#: How long the servers the graph shows must stay the same before send says the robot's is not among
#: them: a fleet whose discovery is still under way shows more servers at each look.  Longer than Fast
#: DDS's participant announcement period (3 s): a process whose first announcements were lost (a
#: loaded machine, a lossy link) shows at its next one (found across hosts with static peers: the
#: graph stood at one shard's robots for over 1.5 s, and send named half the fleet).
SETTLED = 3.5


def _found(
    client: DynamicEventClient,
    node: object,
    args: SendOptions,
    left: Callable[[], float],
    say: Callable[[str], None],
) -> bool:
    """Is the robot's server there?  Discovery can take seconds (a fleet adapter's took 3 s here, and
    more on a loaded machine), so send waits on, to the timeout, while the graph shows no Dynamic
    Event server yet or shows this robot's; once the graph shows other robots' servers and, after
    :data:`LOOK` seconds and with no new one for :data:`SETTLED` seconds, not this one's, it says
    which it sees and stops, unless ``--wait``."""
    waited = float(args.timeout)
    started = waited - left()
    keep_waiting = args.wait
    known: frozenset[tuple[str, str]] = frozenset()
    changed = 0.0  # when the servers the graph shows last changed (discovery still under way)
    while left() > 0:
        if client.wait_for_server(min(WAKE, left())):
            return True
        seen = frozenset(servers_seen(node))
        elapsed = waited - left() - started
        if seen != known:
            known, changed = seen, elapsed
        settled = elapsed - changed >= SETTLED
        if not keep_waiting and elapsed >= LOOK and settled and seen and (args.fleet, args.robot) not in seen:
            # not "within N s": when the graph settles varies from run to run, the verdict does not
            missing = f"no Dynamic Event server for {args.fleet}/{args.robot} once the graph settled"
            say(f"{missing}; {graph_text(node)}")
            return False
    say(no_server_text(node, args.fleet, args.robot, waited))
    return False


def _contact_line(robot: str, change: cl.OutOfContact | cl.BackInContact) -> str:
    """R21.5: a lost contact is said when it is lost, and again when it comes back."""
    if isinstance(change, cl.OutOfContact):
        clock = time.strftime("%H:%M:%S", time.localtime(change.since / SECOND))
        return f"lost contact with {robot} at {clock}; waiting for it to come back"
    lost = (change.now - change.since) / SECOND
    return f"back in contact with {robot} after {lost:.0f} s; asking again for the answer"


def _stop_goal(
    client: DynamicEventClient,
    goal_run: GoalRun,
    event_type: EventType,
    signum: int,
    say: Callable[[str], None],
) -> int:
    """Ctrl-C (or SIGTERM) while the goal was open: a NEXT's child is cancelled (a CANCEL goal naming
    it, once it runs), and send waits, at most :data:`STOP_BOUND` seconds, for the goal's answer;
    what happened is printed.  The exit status is 128 + the signal, as a shell gives it."""
    name = signal.Signals(signum).name
    deadline = time.monotonic() + STOP_BOUND
    if event_type == EventType.NEXT:
        say(
            f"{name}: cancelling the child (a CANCEL naming it); waiting up to {STOP_BOUND:g} s "
            "for the answer"
        )
        client.withdraw(goal_run)  # the client machine sends the CANCEL once the child is known to run
    else:
        say(f"{name}: waiting up to {STOP_BOUND:g} s for the answer to the goal already sent")
    try:
        with interruptible():
            result = goal_run.wait(max(deadline - time.monotonic(), 0.0))
    except GoalWaitTimeout:
        say(f"no answer within {STOP_BOUND:g} s of {name}: the goal may still be open on the robot")
        return 128 + signum
    except Interrupted:
        say(f"{name} again: leaving without the answer")
        return 128 + signum
    if isinstance(result, cl.Refused):
        say(f"{name}: the goal was not sent")
    else:
        say(f"outcome: {result.kind.value}: {result.text}")
    return 128 + signum


def _open_trace(args: SendOptions) -> TraceWriter | None:
    if args.trace is None:
        return None
    try:
        return TraceWriter(args.trace, fleet=args.fleet, robot=args.robot, tap="client")
    except FileError as exc:
        raise SendError(str(exc)) from None


def _why_refused(status: DynamicEventStatus, goal: Goal) -> str:
    """What the status tells of a refusal (a ROS refusal carries no reason)."""
    explanation = explain.explain(status, goal)
    if isinstance(explanation.decision, outs.Accepted):
        unknown = "; ".join(explanation.unknown) or "what the robot supports"
        return (
            "why: the status does not show it: the robot most likely does not support this category "
            f"or description (a status cannot tell: {unknown})"
        )
    return "why: " + explain.format_explanation(explanation).rstrip("\n")


def _status(client: DynamicEventClient) -> DynamicEventStatus:
    state = client.state
    return DynamicEventStatus(
        dynamic_event_seq=state.seq, dynamic_state=state.phase, status=state.status, id=state.current_id
    )
