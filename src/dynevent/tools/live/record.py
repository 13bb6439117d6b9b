"""``dynevent record``: record a live system's Dynamic Event conversations into a rosbag2 bag.

The subscriptions are the ROS binding's (:class:`dynevent.ros.record.Recorder`: every Dynamic Event
name on the graph of the robots asked for, each message written as it arrives, serialised as
received, into an MCAP bag in the rosbag2 layout).  This module opens the bag, shows a progress line
(topics, messages, bytes) on a terminal, and stops cleanly at Ctrl-C, SIGTERM or ``--seconds``: the
bag is closed with its index and metadata, and nothing received is lost.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Callable
from pathlib import Path

import attrs

from dynevent.errors import MissingExtra, RecordError
from dynevent.ros.record import Recorder
from dynevent.ros.spinning import Session
from dynevent.tools._progress import Progress
from dynevent.tools.live import offline, see_the_whole_graph

__all__ = ["RecordOptions", "run"]


@attrs.frozen(kw_only=True)
class RecordOptions:
    """What ``dynevent record`` is asked to do, its flags read and checked by the command line."""

    output: str | None = None  # the bag's directory; by default dynevent_<date>-<time>
    fleets: tuple[str, ...] = ()  # the fleets recorded (every fleet when none)
    robots: tuple[str, ...] = ()  # the robots recorded (every robot when none)
    seconds: float | None = None  # stop after this long (by default at Ctrl-C or SIGTERM)
    ros_args: tuple[str, ...] = ()  # ROS 2's own command-line arguments (``--ros-args ...``)


def run(args: RecordOptions, say: Callable[[str], None]) -> int:
    """Record until SIGINT, SIGTERM or ``--seconds``; 0, or 2 when the bag cannot be written."""
    try:
        from rosbags.rosbag2 import WriterError

        from dynevent.bags.sent import open_writer
    except ImportError:
        raise MissingExtra("bags", "rosbags", "writes rosbag2 recordings") from None
    output = Path(args.output or time.strftime("dynevent_%Y_%m_%d-%H_%M_%S"))
    if os.path.lexists(output):  # lexists: a path too long to stat is for the writer to name
        raise RecordError(f"--output {output}: exists already (a bag is a new directory)")
    fleets, robots = set(args.fleets), set(args.robots)

    def wanted(fleet: str, robot: str) -> bool:
        return (not fleets or fleet in fleets) and (not robots or robot in robots)

    try:
        writer = open_writer(output)
        writer.open()
    except (OSError, WriterError) as exc:
        raise RecordError(f"--output {output}: cannot write: {exc}") from None
    see_the_whole_graph()  # the topics to record are found on the graph
    offline(say)
    session = Session("dynevent_record", args.ros_args)
    progress = Progress(f"recording {output}", interval=0.0)
    say = progress.above(say)  # every line the progress line is erased for
    recorder = Recorder(session.node, writer, wanted, say)

    def show() -> None:
        topics, messages, size = len(recorder.topics), recorder.messages, recorder.bytes
        progress.show(f"{topics} topics, {messages:,} messages, {size:,} bytes")

    recorder.keep_discovering(show)
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    for fleet in sorted(fleets) if robots else ():  # robots named in full: their names are known now
        for robot in sorted(robots):
            recorder.expect(fleet, robot)
    recorder.discover()
    session.start()
    say(f"recording into {output} (Ctrl-C to stop)")
    try:
        stop.wait(args.seconds)
    finally:
        # the bag is closed (its index and metadata.yaml written) before anything that could hang
        session.spinner.stop()
        recorder.close()  # a write in progress ends first; none follows
        writer.close()
        session.close()
        progress.close()
    say(f"recorded {recorder.messages} messages ({recorder.bytes} bytes) on {len(recorder.topics)} topics "
        f"into {output}")  # fmt: skip
    return 0
