"""``dynevent check``: the command that judges a trace or a recording, and prints the judgement.

The judging is :mod:`dynevent.conformance.judge` (the observer, the partial judge, traces) and
:mod:`dynevent.bags` (recordings): this module reads files and standard input, shows progress on a
terminal, and prints findings as text or JSON lines (docs/trace-format.md, docs/recordings.md).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Iterator
from typing import Any

from dynevent import errors as _errors
from dynevent import files
from dynevent.conformance import judge as _judge
from dynevent.errors import FileError
from dynevent.tools._progress import Progress
from dynevent.wire import _json
from dynevent.wire.vocab import Compatibility

__all__ = ["BAG_SUFFIXES", "bag_records", "format_bag", "run"]


def run(args: argparse.Namespace) -> int:
    """``dynevent check TRACE``: judge the trace or recording and print the findings; 0 clean, 1 findings,
    2 unreadable input."""
    source = args.trace
    compatibility = Compatibility(getattr(args, "compatibility", None) or Compatibility.STANDARD)
    if source != "-" and (os.path.isdir(source) or source.endswith(BAG_SUFFIXES)):
        return _run_bag(source, args.json, compatibility)
    try:
        if source == "-":
            report = _check_stream(sys.stdin.buffer, "<stdin>", compatibility)
        else:
            with files.open_regular(source, "trace") as stream:
                report = _check_stream(stream, source, compatibility)
    except FileError as exc:
        print(f"dynevent check: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"dynevent check: {source}: cannot read: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except _errors.TraceError as exc:
        print(f"dynevent check: {exc}", file=sys.stderr)
        return 2
    if report.records == 0:
        print(f"dynevent check: {report.source}: nothing to check: no record in it", file=sys.stderr)
        return 2
    if args.json:
        for row in _judge.trace_records(report):
            print(_json.dumps(row))
    else:
        print(_judge.format_report(report), end="")
    return 0 if report.clean else 1


#: The storage files of a rosbag2 recording that ``dynevent check`` reads as one.
BAG_SUFFIXES = (".mcap", ".db3")


def _run_bag(source: str, as_json: bool, compatibility: Compatibility) -> int:
    from dynevent.bags.reader import check_bag
    from dynevent.errors import BagError, MissingExtra

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
    from dynevent.bags.reader import SEND_GOAL

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
                         "judged anew from a status beside it")  # fmt: skip
        for time, uuid in robot.unheard:
            lines.append(f"{where} @ {_bag_time(time)}: the bag lacks the response to goal {uuid}: read "
                         "as accepted from its feedback, answer, running child or goal status")  # fmt: skip
        for time, seq in robot.unbegun:
            lines.append(f"{where} @ {_bag_time(time)}: the bag lacks the begin of run {seq}: read as begun "
                         "from its first status")  # fmt: skip
        for time, channel, sent in robot.late:
            lines.append(f"{where} @ {_bag_time(time)}: {_late(channel, time, sent)}")
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


def _late(channel: str, time: int, sent: int) -> str:
    """What a message of the server's that came too late to be judged in its place is said as."""
    return (
        f"a {channel} message sent {(time - sent) / 1e9:.1f} s before it was received, after messages "
        "sent later were judged: not judged"
    )


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
        for time, uuid in robot.unheard:
            rows.append({"type": "lost_response", "file": bag.source, "robot": robot.name,
                         "time": _bag_time(time), "goal_uuid": uuid})  # fmt: skip
        for time, seq in robot.unbegun:
            rows.append({"type": "lost_begin", "file": bag.source, "robot": robot.name,
                         "time": _bag_time(time), "seq": seq})  # fmt: skip
        for time, channel, sent in robot.late:
            rows.append({"type": "late", "file": bag.source, "robot": robot.name, "time": _bag_time(time),
                         "channel": channel, "sent": _bag_time(sent)})  # fmt: skip
        if robot.refused:
            rows.append(
                {"type": "refused", "file": bag.source, "robot": robot.name, "messages": robot.refused}
            )
    violations = sum(len(robot.report.findings) for robot in bag.robots)
    rows.append({"type": "summary", "file": bag.source, "robots": len(bag.robots),
                 "messages": bag.messages, "violations": violations})  # fmt: skip
    return rows


def _check_stream(
    stream: Any, source: str, compatibility: Compatibility = Compatibility.STANDARD
) -> _judge.Report:
    """Check a trace read line by line from a binary stream, with a progress line on a terminal."""
    try:
        size: int | None = os.fstat(stream.fileno()).st_size or None
    except (OSError, ValueError, AttributeError):
        size = None
    progress = Progress(f"dynevent check: {source}", size)
    try:
        return _judge.check_trace(_text_lines(stream, source, progress), source, compatibility=compatibility)
    finally:
        progress.close()


#: The longest trace line read (bytes): a record carries at most a description of a megabyte, which
#: JSON's escapes can make six; a longer line is refused before it is held whole.
MAX_TRACE_LINE = 16_000_000


def _lines(stream: Any, source: str) -> Iterator[bytes]:
    """The stream's lines, each read to at most :data:`MAX_TRACE_LINE` bytes."""
    number = 0
    while raw := stream.readline(MAX_TRACE_LINE + 1):
        number += 1
        if len(raw) > MAX_TRACE_LINE and not raw.endswith(b"\n"):
            raise _errors.TraceError(source, number, "$", f"a line longer than {MAX_TRACE_LINE:,} bytes")
        yield raw


def _text_lines(stream: Any, source: str, progress: Progress) -> Iterator[str]:
    done = 0
    for number, raw in enumerate(_lines(stream, source), start=1):
        done += len(raw)
        progress.update(done, f"(line {number:,})")
        try:
            yield raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise _errors.TraceError(
                source, number, "$", f"not UTF-8 text (byte {exc.start} of the line)"
            ) from None
