"""``dynevent serve``: its flags and configuration checked without ROS 2, then the simulated fleet
served over it (:mod:`dynevent.tools.live.serve`)."""

from __future__ import annotations

import argparse
from typing import Any

from dynevent import files
from dynevent.errors import ServeError
from dynevent.sim.config import ServeConfig, load_config
from dynevent.tools.live import run_over_ros, say

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    """``dynevent serve``: serve the fleet until Ctrl-C or ``--seconds``; 0, or 2 for a bad option,
    configuration or state file."""

    def check() -> ServeConfig:
        if not 0 <= args.grace <= 3600:
            raise ServeError(f"--grace: expected seconds from 0 to 3600 (got {args.grace})")
        files.check_writable(args.report, "--report")
        config = load_config(
            args.config, fleet=args.fleet, robots=args.robots or (), rebegin=args.rebegin,
            first_seq=args.first_seq, compatibility=args.compatibility, shard=args.shard,
        )  # fmt: skip
        files.check_writable(args.trace, "--trace", directory=len(config.served()) > 1)  # a file a robot
        return config

    def serve(live: Any, config: ServeConfig) -> int:
        watch = live.Watch(judge=not args.no_judge, grace=args.grace, report=args.report, trace=args.trace,
                           introspection=args.introspection)  # fmt: skip
        return int(live.run(config, args.state, args.seconds, say, watch, args.ros_args))

    return run_over_ros("serve", check, serve)
