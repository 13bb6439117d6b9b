"""``dynevent serve``: a Dynamic Event server for a whole fleet, with simulated child events.

A stand-in for a fleet adapter that client authors can run in a minute: one
process hosting :class:`~dynevent.ros.server.DynamicEventServer` for each
robot (in lanes of :data:`LANE` robots, a node and an executor thread each;
``--shard K/N`` serves one part of the fleet), whose children are simulated
doing what their descriptions say (:func:`~dynevent.sim.config.plan`;
per category a duration, a progress report with a log line every so often,
places on which it fails), every description checked as the fleet adapter
checks it (:mod:`dynevent.descriptions`, with the configured map and actions).
Every robot begins a dynamic event at start, again some seconds after a run
ends (``--rebegin``), and whenever a ``rmf_task_msgs/DynamicEventDescription``
naming it arrives on ``dynevent/serve/begin``. With ``--state FILE`` every robot's state is kept in
a SQLite store (:mod:`dynevent.server.store`); a restart on the same file
continues every run and gives every goal of the dead process its answer (R21).
A readable live log of goals and answers goes to standard output.
"""

from __future__ import annotations

import contextlib
import os
import queue
import signal
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

import attrs
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.logging import LoggingSeverity

from dynevent import files
from dynevent.conformance.clients import ONE_CLIENT, ClientFinding, ClientJudge
from dynevent.conformance.judge.trace import TraceWriter
from dynevent.errors import (
    FileError,
    InvalidConfig,
    InvalidMessage,
    ServeError,  # defined there with every error; importable here too
)
from dynevent.ros import convert, participant, spinning
from dynevent.ros.convert import RosDescription, describe_type
from dynevent.ros.qos import latched
from dynevent.ros.server import ChildExecution, DynamicEventServer
from dynevent.ros.spinning import CLOSE_BOUND, Spinner, bounded_close, close_down
from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig, State
from dynevent.server.store import StateStore
from dynevent.sim.children import SimulatedChild
from dynevent.sim.config import (
    DEFAULT_DESCRIPTION,
    CategorySpec,
    ServeConfig,
    load_config,
    machine_config,
)
from dynevent.wire._text import status_text
from dynevent.wire.vocab import Compatibility

__all__ = ["BEGIN_COMMAND_TOPIC", "CategorySpec", "ServeConfig", "ServeError", "load_config", "run"]

#: Publish a DynamicEventDescription naming a robot here to begin a dynamic event for it.
BEGIN_COMMAND_TOPIC = "dynevent/serve/begin"


class SimulatedChildren:
    """Children that run on the node's timers, doing what their descriptions say (:func:`plan`)."""

    def __init__(self, node: Any, config: ServeConfig, say: Callable[[str], None]) -> None:
        self._node = node
        self._config = config
        self._say = say
        self._timers: dict[ChildExecution, Any] = {}  # by execution: the robots share child ids
        self._lock = threading.Lock()

    def start(self, execution: ChildExecution) -> None:
        child = SimulatedChild(execution.category, execution.parsed, self._config)
        began = time.monotonic()

        def report() -> None:
            if child.report(execution, time.monotonic() - began):
                self._forget(execution)

        with self._lock:
            self._timers[execution] = self._node.create_timer(child.period, report)

    def _forget(self, execution: ChildExecution) -> None:
        with self._lock:
            timer = self._timers.pop(execution, None)
        if timer is not None:
            self._node.destroy_timer(timer)

    def cancel(self, execution: ChildExecution) -> None:
        """The child stops at its next report."""

    def kill(self, execution: ChildExecution) -> None:
        """The child stops at its next report."""

    def interrupt(self, execution: ChildExecution) -> None:
        """Simulated children do not pause."""

    def resume(self, execution: ChildExecution) -> None:
        """Simulated children do not pause."""


def _describe(output: outs.Output | outs.Rejected) -> str | None:
    """One line of the live log, or None for outputs not worth a line."""
    if isinstance(output, outs.Rejected):
        return f"refused: {output.reason.value}: {output.text}"
    if isinstance(output, outs.PublishBegin):
        return f"begin: run {output.message.dynamic_event_seq}"
    if isinstance(output, outs.PublishStatus):
        return f"status: {status_text(output.message)}"
    if isinstance(output, outs.StartChild):
        return f"start: child {output.id} {output.category} {output.description}"
    if isinstance(output, (outs.CancelChild, outs.KillChild)):
        return f"{'kill' if isinstance(output, outs.KillChild) else 'cancel'}: child {output.id}"
    if isinstance(output, outs.AnswerGoal):
        result = output.result
        detail = repr(result.execution_failure.split("\n")[0]) if result.execution_failure else result.status
        # the uuid's last 8 hex: a dynevent client's uuids share a prefix and count up at the end
        return f"answer: goal …{output.goal_uuid[-8:]} {output.status.value}: {detail} id={result.id}"
    if isinstance(output, outs.Log):
        return f"log: {output.entry.tier}: {output.entry.text}"
    if isinstance(output, outs.DynamicEventFinished):
        return f"finished: the dynamic event ended {output.status}"
    return None


@attrs.frozen
class Watch:
    """What ``dynevent serve`` writes and judges besides serving: ``judge`` its clients (docs/spec.md
    section 22) with a ``grace`` period in seconds; ``report`` a Markdown summary of the judgement at
    exit; ``trace`` each robot's steps as a trace (a file for one robot, a directory for several)."""

    judge: bool = True
    grace: float = 0.5
    report: str | None = None
    trace: str | None = None
    #: Publish the action's service events (introspection, with contents) even when not judging.
    introspection: bool = False


class _Clients:
    """Names the clients of a serve process by the GIDs of their action clients (R22.1), in the order
    they are first seen: ``client 1``, ``client 2``..."""

    def __init__(self) -> None:
        self._names: dict[bytes, str] = {}
        self._lock = threading.Lock()

    def name(self, gid: bytes) -> str:
        with self._lock:
            if gid not in self._names:
                self._names[gid] = f"client {len(self._names) + 1} (gid {gid.hex()})"
            return self._names[gid]


class _Judged:
    """One robot's judge of its clients and its trace, fed by the server's steps and, when the action
    server can be introspected, by its ``send_goal`` service events (which name the client)."""

    def __init__(
        self, fleet: str, robot: str, config: ServerConfig, watch: Watch, clients: _Clients,
        say: Callable[[str], None], trace: TraceWriter | None,
    ) -> None:  # fmt: skip
        self.fleet, self.robot, self.say = fleet, robot, say
        self.judge = ClientJudge(fleet, robot, grace=watch.grace, config=config) if watch.judge else None
        self.clients = clients
        self.trace = trace
        self.named = False  # introspection names the clients; else every goal is ONE_CLIENT's
        #: Starts following the robot's goal events (at its first goal); None once done, or never.
        self.follow: Callable[[], None] | None = None
        self.goals = 0
        self._lock = threading.Lock()

    def on_step(self, event: ins.Input, outputs: tuple[outs.Output, ...]) -> None:
        if self.trace is not None:
            self.trace.step(event, outputs)
        if self.judge is None:
            return
        follow = self.follow
        if follow is not None and isinstance(event, (ins.GoalRequested, ins.GoalSubmitted)):
            self.follow = None
            follow()
        with self._lock:
            if isinstance(event, (ins.GoalRequested, ins.GoalSubmitted)) and not self.named:
                self._report(self.judge.goal(ONE_CLIENT, event.goal_uuid, event.goal, event.now))
            self.judge.step(event, outputs)

    def on_goal_event(self, message: Any) -> None:
        """A ``send_goal`` service event: a request received names its client and its goal."""
        if self.judge is None or message.info.event_type != _REQUEST_RECEIVED or not message.request:
            return
        request = message.request[0]
        try:
            goal = convert.goal_from_ros(request.goal)
            uuid = convert.uuid_from_ros(request.goal_id)
        except (InvalidMessage, ValueError):
            return  # the server refuses it as it stands; nothing a judge of clients adds
        client = self.clients.name(bytes(message.info.client_gid))
        arrived = message.info.stamp.sec * 1_000_000_000 + message.info.stamp.nanosec
        with self._lock:
            self._report(self.judge.goal(client, uuid, goal, arrived))

    def _report(self, found: list[ClientFinding]) -> None:
        self.goals += 1
        for finding in found:
            self.say(f"{self.fleet}/{self.robot}  client judge: {finding.line()}")

    def close(self, now: int) -> None:
        if self.judge is not None:
            with self._lock:
                for finding in self.judge.close(now):
                    self.say(f"{self.fleet}/{self.robot}  client judge: {finding.line()}")
        if self.trace is not None:
            self.trace.close()


#: ``service_msgs/ServiceEventInfo.REQUEST_RECEIVED``.
_REQUEST_RECEIVED = 1


def judgement(judged: list[_Judged]) -> tuple[str, str]:
    """The judgement of the clients at exit: one line for the live log, and a Markdown report."""
    findings = [finding for item in judged if item.judge is not None for finding in item.judge.findings]
    goals = sum(item.goals for item in judged)
    by_client: dict[str, dict[str, int]] = {}
    for finding in findings:
        rules = by_client.setdefault(finding.client, {})
        key = f"{finding.rule} {finding.violation.code}"
        rules[key] = rules.get(key, 0) + 1
    parts = [f"{client}: " + ", ".join(f"{key} x{count}" for key, count in sorted(rules.items()))
             for client, rules in sorted(by_client.items())]  # fmt: skip
    line = f"client judgement: {goals} goal(s) judged, {len(findings) or 'no'} finding(s)"
    line += ("; " + "; ".join(parts)) if parts else ""
    report = ["# dynevent serve: the judgement of its clients", "", line, ""]
    report += ["| time | robot | client | rule | sent | could know |", "|---|---|---|---|---|---|"]
    for finding in sorted(findings, key=lambda item: item.time):
        stamp = (
            time.strftime("%H:%M:%S", time.gmtime(finding.time / 1e9))
            + f".{finding.time % 10**9 // 10**6:03d}"
        )
        cells = [stamp, finding.robot, finding.client, f"{finding.rule} `{finding.violation.code}`",
                 finding.sent, finding.knew]  # fmt: skip
        report.append("| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |")
    return line, "\n".join(report) + "\n"


#: Robots per lane: one node and one executor thread each.  rclpy's executor walks every entity of
#: its nodes at each wake-up, so a wake-up costs in proportion to the robots it serves: 2,000 robots
#: on one executor served 56 goals a second per core, in lanes of 64 several times more
#: (docs/performance.md).  The lanes' threads share the GIL; a lane waits for DDS without it.
LANE = int(os.environ.get("DYNEVENT_SERVE_LANE", "64"))


class _Lane:
    """A node, its own single-threaded executor and thread, and the simulated children of its robots."""

    def __init__(self, name: str, config: ServeConfig, say: Callable[[str], None]) -> None:
        self.node = rclpy.create_node(name)
        self.node.get_logger().set_level(LoggingSeverity.WARN)  # the live log says the rest
        self.children = SimulatedChildren(self.node, config, say)
        self.executor = SingleThreadedExecutor()
        self.spinner = Spinner(self.executor, f"dynevent-serve-{name}")

    def spin(self) -> None:
        self.executor.add_node(self.node)
        self.spinner.start()

    def stop(self) -> None:
        self.spinner.stop()


class _JudgeLane:
    """The node that follows the robots' ``send_goal`` service events for the judge, in a context (a
    DDS participant) of its own: serve's participants match none of their own endpoints
    (:mod:`dynevent.ros.participant`), so the events are heard as another process would hear them."""

    def __init__(self, name: str, ros_args: Sequence[str]) -> None:
        self.context = participant.own_context(ros_args)
        self.node = rclpy.create_node(name, context=self.context)
        self.node.get_logger().set_level(LoggingSeverity.WARN)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.spinner = Spinner(self.executor, f"dynevent-serve-{name}")

    def spin(self) -> None:
        self.executor.add_node(self.node)
        self.spinner.start()

    def close(self) -> None:
        self.spinner.stop()
        close_down([self.node], self.context)


#: How much longer than :data:`~dynevent.ros.spinning.CLOSE_BOUND` a close-down may take per robot
#: served (seconds): destroying the entities of a fleet costs more the more there are.
CLOSE_PER_ROBOT = 0.1


class _Robots:
    """The robots one ``dynevent serve`` process serves: their servers, lanes, live log and re-begins."""

    def __init__(
        self,
        config: ServeConfig,
        machine_config: ServerConfig,
        store: StateStore | None,
        say: Callable[[str], None],
        watch: Watch | None = None,
        ros_args: Sequence[str] = (),
    ) -> None:
        self.config = config
        self.store = store
        self.say = say
        self.watch = watch or Watch()
        self.clients = _Clients()
        self.judged: list[_Judged] = []
        self.machine_config = machine_config
        index, count = config.shard
        base = "dynevent_serve" if count == 1 else f"dynevent_serve_{index}_of_{count}"
        robots = config.served()
        self.lanes = [
            _Lane(base if start == 0 else f"{base}_lane_{start // LANE}", config, say)
            for start in range(0, max(len(robots), 1), LANE)
        ]
        self.lane_of = {robot: self.lanes[position // LANE] for position, robot in enumerate(robots)}
        self.judge_lane = _JudgeLane(f"{base}_judge", ros_args) if self.watch.judge else None
        self.node = self.lanes[0].node  # the fleet-wide begin publisher and the begin commands
        self.begins = DynamicEventServer.fleet_begin_publisher(self.node)
        self.servers: dict[str, DynamicEventServer] = {}
        self.rebegin_timers: dict[str, Any] = {}
        # the description query (R16) as dynevent offers it; rmf_ros2 has none (D17), nor has a
        # rmf_task_msgs without the project's DescribeDynamicEvent
        self.description_service = describe_type() if config.offers_description else None
        self._timers_lock = threading.Lock()  # begin commands arrive on lane 0's thread

    def observer(self, robot: str) -> Callable[[outs.Output | outs.Rejected], None]:
        def observe(output: outs.Output | outs.Rejected) -> None:
            line = _describe(output)
            if line is not None:
                self.say(f"{self.config.fleet}/{robot}  {line}")

        return observe

    def finished(self, robot: str) -> Callable[[str], None]:
        def rebegin_later(status: str) -> None:
            if self.config.rebegin > 0:
                node = self.lane_of[robot].node
                timer = node.create_timer(self.config.rebegin, lambda: self.begin_again(robot))
                with self._timers_lock:
                    self.rebegin_timers[robot] = timer

        return rebegin_later

    def begin_again(self, robot: str, description: str = DEFAULT_DESCRIPTION) -> None:
        with self._timers_lock:
            timer = self.rebegin_timers.pop(robot, None)
        if timer is not None:
            self.lane_of[robot].node.destroy_timer(timer)
        self.servers[robot].begin(description, 1)

    def add(self, robot: str, restored: State | None) -> None:
        """Serve ``robot``, from its restored state if any; a robot with no active run begins one."""
        fleet, store, lane = self.config.fleet, self.store, self.lane_of[robot]
        judged = _Judged(fleet, robot, self.machine_config, self.watch, self.clients, self.say,
                         self._trace(robot))  # fmt: skip
        self.judged.append(judged)
        server = DynamicEventServer(
            lane.node,
            fleet,
            robot,
            self.machine_config,
            lane.children,
            begin_publisher=self.begins,
            description_service=self.description_service,
            state=restored or self.config.first_state(robot),
            on_state=store.save if store is not None else None,
            on_answers=(lambda answers: store.keep_answers(fleet, robot, answers)) if store else None,
            answers=store.answers(fleet, robot) if store is not None else None,
            observer=self.observer(robot),
            on_finished=self.finished(robot),
            on_step=judged.on_step,
        )
        if self.watch.judge or self.watch.introspection:  # a recording of serve then holds the goals
            judged.named = server.introspect()
        if self.judge_lane is not None and judged.named:
            # the judge follows a robot's goal events, which name the clients, from its first goal on
            # (the events kept include that goal's): 1,000 followers at once, each paired with every
            # endpoint of the robots' participant, would take half a minute to start
            follower = self.judge_lane.node
            judged.follow = lambda: server.follow(judged.on_goal_event, follower)
        self.servers[robot] = server
        if restored is not None:
            self.say(f"{fleet}/{robot}  restored: run {restored.seq}, last id {restored.last_id}")
            server.restart()
        if not server.state.active:
            server.begin(DEFAULT_DESCRIPTION, 1)

    def _trace(self, robot: str) -> TraceWriter | None:
        path = self.watch.trace
        if path is None:
            return None
        if len(self.config.served()) > 1:
            path = os.path.join(path, f"{robot}.jsonl")
        try:
            return TraceWriter(path, fleet=self.config.fleet, robot=robot)
        except FileError as exc:
            raise ServeError(str(exc)) from None

    def on_begin_command(self, message: Any) -> None:
        if message.fleet == self.config.fleet and message.robot in self.servers:
            self.begin_again(message.robot, message.description or DEFAULT_DESCRIPTION)


def run(
    config: ServeConfig,
    state_path: str | None,
    seconds: float | None,
    say: Callable[[str], None],
    watch: Watch | None = None,
    ros_args: Sequence[str] = (),
) -> int:
    """Serve until SIGINT or SIGTERM (or ``seconds``); 0, or 2 for a store or configuration refused.
    ``ros_args`` are the command line's ROS arguments (``--ros-args ...``), given to rclpy."""
    store = StateStore(state_path) if state_path is not None else None  # InvalidStore: nothing written
    stored = store.load() if store is not None else {}
    try:
        checking = machine_config(config)
    except InvalidConfig as exc:
        raise ServeError(str(exc)) from None
    log = LiveLog(say)
    why_slow = participant.ignore_own_endpoints()  # before the first participant: a fast start
    if why_slow and len(config.served()) > LANE:
        log(why_slow)
    spinning.init(ros_args)
    # Single-threaded executors, one per lane: a multi-threaded one adds its own work and Python's
    # GIL runs one thread at a time anyway.  rclpy's EventsExecutor (rclpy 9.1.2, rclpy.experimental)
    # cannot serve the binding: it refuses guard conditions and hangs at 100% CPU on an action server
    # whose execute callback is a coroutine (docs/performance.md).
    watch = watch or Watch()
    if watch.trace is not None and len(config.served()) > 1:
        with contextlib.suppress(FileExistsError):
            os.mkdir(watch.trace)
    robots = _Robots(config, checking, store, log, watch, ros_args)
    for robot in config.served():
        robots.add(robot, stored.get((config.fleet, robot)))
    robots.node.create_subscription(RosDescription, BEGIN_COMMAND_TOPIC, robots.on_begin_command, latched(10))
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    for lane in robots.lanes:
        lane.spin()
    if robots.judge_lane is not None:
        robots.judge_lane.spin()
    log(_banner(config, list(robots.servers), robots.node.get_namespace()))
    stop.wait(seconds)
    now = time.time_ns()
    for judged in robots.judged:  # before the shutdown ends every run
        judged.close(now)
    for server in robots.servers.values():
        server.shutdown()
    time.sleep(0.2)  # let the shutdown answers go out before the node goes
    with bounded_close():
        for lane in robots.lanes:
            lane.stop()
        if robots.judge_lane is not None:
            robots.judge_lane.spinner.stop()
    # what the run leaves (the store, the judgement) before the entities go: destroying a fleet's
    # entities takes time in proportion to the square of their number (docs/performance.md)
    if store is not None:
        store.close()
    if watch.judge:
        line, report = judgement(robots.judged)
        log(line)
        if watch.report is not None:
            try:
                files.write_text(watch.report, report, "--report")
            except FileError as exc:
                log(str(exc))
    with bounded_close(CLOSE_BOUND + CLOSE_PER_ROBOT * len(robots.servers)):
        for server in robots.servers.values():
            server.destroy()
        if robots.judge_lane is not None:
            robots.judge_lane.close()
        close_down([lane.node for lane in robots.lanes])
    log.close()
    return 0


def _banner(config: ServeConfig, names: list[str], space: str) -> str:
    """The line serve says once its robots are on the graph: how many, of which fleet, in which
    namespace (``--ros-args -r __ns:=/site`` puts every name under it), shard and mode."""
    index, count = config.shard
    shown = ", ".join(names if len(names) <= 10 else [*names[:10], f"... ({len(names) - 10} more)"])
    part = "" if count == 1 else f" (shard {index}/{count} of {len(config.robots)})"
    mode = "as rmf_ros2 behaves" if config.compatibility is Compatibility.RMF_ROS2 else "as the spec says"
    inside = "" if space == "/" else f" in namespace {space}"
    fleet = f"fleet {config.fleet}{inside}{part}"
    return f"serving {len(names)} robot(s) of {fleet}, {config.compatibility.value} mode ({mode}): {shown}"


class LiveLog:
    """The live log, written by a thread of its own: the executor's thread only queues a line, and
    the writer takes every line queued since its last write in one write (a busy fleet logs several
    lines per goal, and a line-by-line write and flush on the executor's thread cost it 14% of its
    time)."""

    def __init__(self, say: Callable[[str], None]) -> None:
        self._say = say
        self._lines: queue.SimpleQueue[str | None] = queue.SimpleQueue()
        self._writer = threading.Thread(target=self._write, daemon=True, name="dynevent-serve-log")
        self._writer.start()

    def __call__(self, line: str) -> None:
        self._lines.put(line)

    def _write(self) -> None:
        while True:
            batch = [self._lines.get()]
            with contextlib.suppress(queue.Empty):
                while len(batch) < 1000 and batch[-1] is not None:
                    batch.append(self._lines.get_nowait())
            lines = [line for line in batch if line is not None]
            if lines:
                self._say("\n".join(lines))
            if batch[-1] is None:
                return

    def close(self) -> None:
        """Write what is queued, then stop the writer (bounded: 5 s)."""
        self._lines.put(None)
        self._writer.join(timeout=5)
