"""``dynevent check``: replay an observed trace of one robot against the machine, in observer mode.

A trace (docs/trace-format.md) is what was seen on the wire for one robot:
begin and status messages, goal requests with their UUIDs, goal responses,
feedback, terminal answers and action-level cancels, each with its time.
The observer keeps a server state (:class:`dynevent.server.machine.State`) and
infers the server's inputs from what it sees:

- a ``begin`` is a ``Begin`` input (the event id arrives with the status
  message that follows);
- a ``goal`` and its ``goal_response`` are a ``GoalRequested`` input: the
  machine's decision is compared with the response;
- every other observation must be an output of the machine.  An
  observation the machine already owes (an output of an inferred step not
  seen yet) is compared with it.  Otherwise the observer *abduces* the
  input that produced it from a short, fixed list of candidates: the start
  of an accepted goal (``GoalStarted``), a child's progress (``ChildProgress``,
  from feedback), a child's end (``ChildFinished``, from the running goal's
  answer), a task cancel or kill, an interruption or a resume, a shutdown.
  The first candidate whose first output on the action (or whose status
  message) is the observation is taken; its other outputs are owed.

When no candidate explains an observation, or the machine's output differs
from it, the observer reports a :class:`Finding` (line, docs/spec.md rule,
code, what was seen, what was expected), then resynchronises with the
smallest change that makes the state agree with what the server evidently
did (it queues a goal the server accepted, starts a NEXT whose feedback
shows it running, forgets goals the server displaced), so that one fault is
reported once and later records are judged against the server's real
condition.

:func:`check_trace` is the API; :func:`read_trace` parses a trace and raises
:class:`TraceError` (naming the source, line and field) on unreadable input.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Iterable, Iterator
from typing import Any

import attrs

from dynevent.errors import (
    TraceError,  # defined there with every error; importable here too
)
from dynevent.tools._progress import Progress
from dynevent.tools.check.observer import check_records
from dynevent.tools.check.trace import (
    RECORD_TYPES,
    Finding,
    Record,
    Report,
    read_trace,
    step_records,
    stream_trace,
)
from dynevent.wire import _json
from dynevent.wire.vocab import Compatibility

__all__ = [
    "RECORD_TYPES",
    "Finding",
    "Record",
    "Report",
    "TraceError",
    "check_records",
    "check_trace",
    "format_report",
    "read_trace",
    "step_records",
    "trace_records",
]


def check_trace(
    text: str | Iterable[str],
    source: str = "<trace>",
    *,
    compatibility: Compatibility | str = Compatibility.STANDARD,
) -> Report:
    """Check a trace (its text, or its lines) in observer mode; each violation is a :class:`Finding`.

    ``compatibility="rmf_ros2"`` judges the server as ``dynevent serve --compatibility rmf_ros2``
    behaves (R17, and the adapter's own numbering of children), where the trace has no config record
    that says otherwise: what is left is where the server differs from that emulation.  Raises
    :class:`TraceError` (naming ``source``, the line and the field) when the trace cannot be read.
    """
    lines = text.splitlines() if isinstance(text, str) else text
    header, records = stream_trace(lines, source)
    header = attrs.evolve(header, compatibility=Compatibility(compatibility))
    return check_records(header, records, source)


def format_report(report: Report) -> str:
    """The findings as text, one per line with what was expected, then a summary line."""
    lines = []
    for finding in report.findings:
        lines.append(f"{report.source}:{finding.line}: {finding.rule} {finding.code}: {finding.message}")
        lines.append(f"    expected: {finding.expected}")
    count = len(report.findings)
    noun = "violation" if count == 1 else "violations"
    summary = f"{report.source}: {report.records} records, {count or 'no'} {noun}"
    lines.append(summary)
    return "\n".join(lines) + "\n"


def trace_records(report: Report) -> list[dict[str, Any]]:
    """The JSON lines of ``dynevent check --json``: one object per finding, then a summary."""
    rows: list[dict[str, Any]] = [
        {"type": "violation", "file": report.source, **finding.to_dict()} for finding in report.findings
    ]
    rows.append(
        {
            "type": "summary",
            "file": report.source,
            "records": report.records,
            "violations": len(report.findings),
        }
    )
    return rows


def _run(args: argparse.Namespace) -> int:
    source = args.trace
    compatibility = Compatibility(getattr(args, "compatibility", None) or Compatibility.STANDARD)
    if source != "-" and (os.path.isdir(source) or source.endswith(BAG_SUFFIXES)):
        return _run_bag(source, args.json, compatibility)
    try:
        if source == "-":
            report = _check_stream(sys.stdin.buffer, "<stdin>", compatibility)
        else:
            with open(source, "rb") as stream:
                report = _check_stream(stream, source, compatibility)
    except OSError as exc:
        print(f"dynevent check: {source}: cannot read: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except TraceError as exc:
        print(f"dynevent check: {exc}", file=sys.stderr)
        return 2
    if report.records == 0:
        print(f"dynevent check: {report.source}: nothing to check: no record in it", file=sys.stderr)
        return 2
    if args.json:
        for row in trace_records(report):
            print(_json.dumps(row))
    else:
        print(format_report(report), end="")
    return 0 if report.clean else 1


#: The storage files of a rosbag2 recording that ``dynevent check`` reads as one.
BAG_SUFFIXES = (".mcap", ".db3")


def _run_bag(source: str, as_json: bool, compatibility: Compatibility) -> int:
    from dynevent.errors import BagError, MissingExtra
    from dynevent.tools.check.bags import check_bag

    try:
        bag = check_bag(source, compatibility=compatibility)
    except (BagError, MissingExtra) as exc:
        print(f"dynevent check: {exc}", file=sys.stderr)
        return 2
    if not bag.robots or not bag.messages:
        others = f"{bag.other} other message{'' if bag.other == 1 else 's'}"
        print(f"dynevent check: {source}: nothing to check: no message on a Dynamic Event name ({others})",
              file=sys.stderr)  # fmt: skip
        return 2
    if as_json:
        for row in bag_records(bag):
            print(_json.dumps(row))
    else:
        print(format_bag(bag), end="")
    return 0 if bag.clean else 1


def format_bag(bag: Any) -> str:
    """A bag's findings as text: per robot each violation at its bag time, and the channels the bag
    lacked (a partial view: only what the topics show was judged); then a summary line."""
    from dynevent.tools.check.bags import SEND_GOAL

    lines = []
    # introspection was on where any robot's goals were recorded: a robot without any had no goals
    introspected = any(SEND_GOAL in robot.channels for robot in bag.robots)
    for robot in bag.robots:
        where = f"{bag.source}: {robot.name}"
        for finding in robot.report.findings:
            lines.append(
                f"{where} @ {_bag_time(finding.line)}: {finding.rule} {finding.code}: {finding.message}"
            )
            lines.append(f"    expected: {finding.expected}")
        if robot.partial and introspected and SEND_GOAL not in robot.channels:
            lines.append(f"{where}: this robot had no goals in the recording (the action's introspection "
                         "was on): judged from its topics alone")  # fmt: skip
        elif robot.partial:
            lines.append(f"{where}: partial view, judged from its topics alone (statuses, begins, feedback, "
                         f"goal statuses): the bag lacks {', '.join(robot.absent)}")  # fmt: skip
        elif robot.absent:
            lines.append(f"{where}: partial view: the bag lacks {', '.join(robot.absent)}")
        for time, uuid in robot.lost:
            lines.append(f"{where} @ {_bag_time(time)}: the bag lacks the request of goal {uuid}: "
                         "judged anew from the status before it")  # fmt: skip
        if robot.refused:
            lines.append(f"{where}: {robot.refused} message(s) the mirrors refuse, not judged")
        count = len(robot.report.findings)
        lines.append(
            f"{where}: {robot.report.records} records, {count or 'no'} violation{'s' if count != 1 else ''}"
        )
    total = sum(len(robot.report.findings) for robot in bag.robots)
    full = sum(1 for robot in bag.robots if not robot.partial)
    lines.append(
        f"{bag.source}: {len(bag.robots)} robot(s), {full} judged in full, {bag.messages} messages, "
        f"{total or 'no'} violation{'s' if total != 1 else ''}"
    )
    return "\n".join(lines) + "\n"


def _bag_time(nanoseconds: int) -> str:
    """A bag time: seconds since the epoch, to the nanosecond, as rosbag2 keeps it."""
    return f"{nanoseconds // 10**9}.{nanoseconds % 10**9:09d}"


def bag_records(bag: Any) -> list[dict[str, Any]]:
    """The JSON lines of ``dynevent check --json`` for a bag: a violation per finding (its bag time in
    ``time``), a partial view per robot that lacked channels, a lost request per goal whose request
    the bag lacked, then a summary."""
    rows: list[dict[str, Any]] = []
    for robot in bag.robots:
        for finding in robot.report.findings:
            row = {"type": "violation", "file": bag.source, "robot": robot.name, **finding.to_dict()}
            row["time"] = _bag_time(row.pop("line"))
            rows.append(row)
        if robot.absent:
            rows.append({"type": "partial_view", "file": bag.source, "robot": robot.name,
                         "absent": list(robot.absent), "full": not robot.partial})  # fmt: skip
        for time, uuid in robot.lost:
            rows.append({"type": "lost_request", "file": bag.source, "robot": robot.name,
                         "time": _bag_time(time), "goal_uuid": uuid})  # fmt: skip
        if robot.refused:
            rows.append(
                {"type": "refused", "file": bag.source, "robot": robot.name, "messages": robot.refused}
            )
    violations = sum(len(robot.report.findings) for robot in bag.robots)
    rows.append({"type": "summary", "file": bag.source, "robots": len(bag.robots),
                 "messages": bag.messages, "violations": violations})  # fmt: skip
    return rows


def _check_stream(stream: Any, source: str, compatibility: Compatibility = Compatibility.STANDARD) -> Report:
    """Check a trace read line by line from a binary stream, with a progress line on a terminal."""
    try:
        size: int | None = os.fstat(stream.fileno()).st_size or None
    except (OSError, ValueError, AttributeError):
        size = None
    progress = Progress(f"dynevent check: {source}", size)
    try:
        return check_trace(_text_lines(stream, source, progress), source, compatibility=compatibility)
    finally:
        progress.close()


def _text_lines(stream: Any, source: str, progress: Progress) -> Iterator[str]:
    done = 0
    for number, raw in enumerate(stream, start=1):
        done += len(raw)
        progress.update(done, f"(line {number:,})")
        try:
            yield raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise TraceError(source, number, "$", f"not UTF-8 text (byte {exc.start} of the line)") from None
