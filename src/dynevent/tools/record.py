"""``dynevent record``: its flags checked without ROS 2, then the live graph recorded into a bag
(:mod:`dynevent.tools.live.record`)."""

from __future__ import annotations

import argparse
import os
from typing import Any

from dynevent import files
from dynevent.errors import RecordError
from dynevent.tools.live import run_over_ros, say

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    """``dynevent record``: record until Ctrl-C or ``--seconds``; 0, or 2 for a bad option or an output
    that cannot be written."""

    def check() -> None:
        if args.seconds is not None and not 0 < args.seconds < 1e9:
            raise RecordError(f"--seconds: expected positive seconds (got {args.seconds})")
        if args.output and os.path.lexists(args.output):  # lexists: a path too long to stat is not there
            raise RecordError(f"--output {args.output}: exists already (a bag is a new directory)")
        if args.all and (args.fleet or args.robot):
            named = "--fleet" if args.fleet else "--robot"
            raise RecordError(f"--all: records every robot of every fleet, so {named} cannot narrow it")
        files.check_writable(args.output, "--output", directory=True)

    def record(live: Any, _: None) -> int:
        options = live.RecordOptions(
            output=args.output, fleets=tuple(args.fleet or ()), robots=tuple(args.robot or ()),
            seconds=args.seconds, ros_args=tuple(args.ros_args),
        )  # fmt: skip
        return int(live.run(options, say))

    return run_over_ros("record", check, record)
