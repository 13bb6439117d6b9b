"""``dynevent serve``: a Dynamic Event server for a whole fleet, with simulated child events.

A stand-in for a fleet adapter that client authors can run in a minute: one
process hosting :class:`~dynevent.ros.server.DynamicEventServer` for each
robot (:class:`dynevent.ros.fleet.Fleet`, in lanes of robots, a node and an executor thread each;
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
A readable live log of goals and answers goes to standard output, and the clients are judged
(docs/spec.md section 22).
"""

from __future__ import annotations

import contextlib
import os
import queue
import signal
import threading
import time
import traceback
from collections.abc import Callable, Sequence
from pathlib import Path

import attrs

from dynevent import files
from dynevent.conformance.judge.clients import ONE_CLIENT, ClientFinding, ClientJudge
from dynevent.conformance.judge.trace import TraceWriter
from dynevent.errors import (
    FileError,
    InvalidConfig,
    ServeError,  # defined there with every error; importable here too
)
from dynevent.ros import participant, spinning
from dynevent.ros.fleet import LANE, Fleet, GoalEvent
from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig
from dynevent.server.store import StateStore
from dynevent.sim.config import ServeConfig, machine_config
from dynevent.tools.live import offline
from dynevent.wire._text import status_text
from dynevent.wire.vocab import Compatibility

__all__ = ["CALLBACK_FAULT", "Watch", "run"]

#: What the live log says of an exception a callback of a lane raised (its robots are served on).
CALLBACK_FAULT = "a callback raised"


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
    if isinstance(output, outs.InterruptConfirmed):
        return "interrupted: the task (a child that starts now waits for the resume)"
    if isinstance(output, (outs.InterruptChild, outs.ResumeChild)):
        return f"{'interrupt' if isinstance(output, outs.InterruptChild) else 'resume'}: child {output.id}"
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
    server can be introspected, by its goal requests as received (which name the client)."""

    def __init__(
        self, fleet: str, robot: str, config: ServerConfig, watch: Watch, clients: _Clients,
        say: Callable[[str], None], trace: TraceWriter | None,
    ) -> None:  # fmt: skip
        self.fleet, self.robot, self.say = fleet, robot, say
        self.judge = ClientJudge(fleet, robot, grace=watch.grace, config=config) if watch.judge else None
        self.clients = clients
        self.trace = trace
        self.named = False  # introspection names the clients; else every goal is ONE_CLIENT's
        self.goals = 0
        self._lock = threading.Lock()

    def on_step(self, event: ins.Input, outputs: tuple[outs.Output, ...]) -> None:
        if self.trace is not None:
            self.trace.step(event, outputs)
        if self.judge is None:
            return
        with self._lock:
            if isinstance(event, (ins.GoalRequested, ins.GoalSubmitted)) and not self.named:
                self._report(self.judge.goal(ONE_CLIENT, event.goal_uuid, event.goal, event.now))
            self.judge.step(event, outputs)

    def on_goal(self, event: GoalEvent) -> None:
        """A goal request as the action server received it names its client and its goal."""
        if self.judge is None:
            return
        client = self.clients.name(event.client_gid)
        with self._lock:
            self._report(self.judge.goal(client, event.goal_uuid, event.goal, event.arrived))

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
    offline(log)
    why_slow = participant.ignore_own_endpoints()  # before the first participant: a fast start
    if why_slow and len(config.served()) > LANE:
        log(why_slow)
    spinning.init(ros_args)  # the fleet's lanes are in the default context
    # Single-threaded executors, one per lane: a multi-threaded one adds its own work and Python's
    # GIL runs one thread at a time anyway.  rclpy's EventsExecutor (rclpy 9.1.2, rclpy.experimental)
    # cannot serve the binding: it refuses guard conditions and hangs at 100% CPU on an action server
    # whose execute callback is a coroutine (docs/performance.md).
    watch = watch or Watch()
    if watch.trace is not None and len(config.served()) > 1:
        try:
            files.create_directory(watch.trace, "--trace")
        except FileError as exc:
            raise ServeError(str(exc)) from None
    fleet = Fleet(config, checking, store, follow=watch.judge, ros_args=ros_args, on_fault=_fault_said(log))
    clients, judged = _Clients(), []
    for robot in config.served():
        judge = _Judged(config.fleet, robot, checking, watch, clients, log, _trace(config, watch, robot))
        restored = stored.get((config.fleet, robot))
        if restored is not None:
            log(f"{config.fleet}/{robot}  restored: run {restored.seq}, last id {restored.last_id}")
        judge.named = fleet.add(
            robot, restored, observer=_observer(config.fleet, robot, log), on_step=judge.on_step,
            introspection=watch.judge or watch.introspection,  # a recording of serve then holds the goals
            on_goal=judge.on_goal if watch.judge else None,
        )  # fmt: skip
        judged.append(judge)
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    fleet.start()
    log(_banner(config, list(fleet.servers), fleet.node.get_namespace()))
    stop.wait(seconds)
    now = time.time_ns()
    for judge in judged:  # before the shutdown ends every run
        judge.close(now)
    fleet.shut_down()
    # what the run leaves (the store, the judgement) before the entities go (Fleet.destroy)
    if store is not None:
        store.close()
    if watch.judge:
        line, report = judgement(judged)
        log(line)
        if watch.report is not None:
            try:
                files.write_text(watch.report, report, "--report")
            except FileError as exc:
                log(str(exc))
    fleet.destroy()
    log.close()
    return 0


def _observer(
    fleet: str, robot: str, say: Callable[[str], None]
) -> Callable[[outs.Output | outs.Rejected], None]:
    """The live log's lines of ``robot``'s outputs and refusals."""

    def observe(output: outs.Output | outs.Rejected) -> None:
        line = _describe(output)
        if line is not None:
            say(f"{fleet}/{robot}  {line}")

    return observe


def _fault_said(say: Callable[[str], None]) -> Callable[[str, Exception], None]:
    """The live log's line of an exception a callback of a lane raised: one line, where it was raised
    (no traceback), and that the lane spins on.  The same fault again (its lane, type and place) is
    said the 10th, 100th, ... time, with its count."""
    seen: dict[tuple[str, str, str], int] = {}

    def said(lane: str, fault: Exception) -> None:
        frames = traceback.extract_tb(fault.__traceback__)
        where = f" at {Path(frames[-1].filename).name}:{frames[-1].lineno}" if frames else ""
        key = (lane, type(fault).__name__, where)
        count = seen[key] = seen.get(key, 0) + 1
        if count > 1 and str(count).rstrip("0") != "1":
            return
        what = str(fault).splitlines()[0] if str(fault) else ""
        again = f" ({count} times)" if count > 1 else ""
        say(f"{lane}: {CALLBACK_FAULT} {type(fault).__name__}{': ' + what if what else ''}{where}{again}; "
            "its robots are served on (a defect: please report it)")  # fmt: skip

    return said


def _trace(config: ServeConfig, watch: Watch, robot: str) -> TraceWriter | None:
    """The trace ``robot``'s steps are written to, if any: a file for one robot, ``ROBOT.jsonl`` in a
    directory for several."""
    path = watch.trace
    if path is None:
        return None
    if len(config.served()) > 1:
        path = os.path.join(path, f"{robot}.jsonl")
    try:
        return TraceWriter(path, fleet=config.fleet, robot=robot)
    except FileError as exc:
        raise ServeError(str(exc)) from None


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
