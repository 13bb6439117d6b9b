"""``dynevent probe``: its flags checked without ROS 2, then the cases run over ROS 2
(:mod:`dynevent.tools.live.probe`), or in this process: ``--loopback`` (dynevent's own machine, as
``dynevent serve`` runs the robot) and ``--impl CMD`` (an implementation behind the driver
protocol), both on simulated time (:mod:`dynevent.conformance.probe.in_process`).  Every report is
written through :func:`dynevent.files.write_text`."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import Any

import attrs

from dynevent import files
from dynevent.conformance.probe import cases as probe_cases
from dynevent.conformance.probe import in_process
from dynevent.conformance.probe import runner as probe_runner
from dynevent.errors import DyneventError, ProbeError
from dynevent.sim.config import ServeConfig, load_config, machine_config
from dynevent.tools.live import run_over_ros, say

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    """``dynevent probe``: run the cases and print the findings; 0 none failed, 1 a case failed, 2 bad
    usage or no server, 3 a case missing that was not expected to be."""

    def check() -> list[probe_cases.Case]:
        cases = probe_cases.select(args.cases)
        if not cases:
            raise ProbeError(f"--cases {' '.join(args.cases)}: no case matches (see dynevent probe --list)")
        for flag in ("timeout", "server_wait", "deadline"):
            if not 0 < getattr(args, flag) < 1e6:
                raise ProbeError(
                    f"--{flag.replace('_', '-')}: expected positive seconds (got {getattr(args, flag)})"
                )
        if not 0 <= args.stubborn_minimum < 1e6:
            raise ProbeError(f"--stubborn-minimum: expected seconds from 0 (got {args.stubborn_minimum})")
        for flag in ("junit", "report", "trace"):
            files.check_writable(getattr(args, flag), f"--{flag}")
        _check_task_commands(args)
        return cases

    if args.list:
        try:
            sys.stdout.write(probe_cases.format_list(check()))
        except DyneventError as exc:
            print(f"dynevent probe: {exc}", file=sys.stderr)
            return 2
        return 0
    if args.loopback or args.impl:
        return _in_process(args, check)

    def probe(live: Any, cases: list[probe_cases.Case]) -> int:
        return int(live.main(_options(args), cases, say))

    return run_over_ros("probe", check, probe)


def _check_task_commands(args: argparse.Namespace) -> None:
    """``--interrupt-command`` and ``--resume-command`` come together, and only for a live server."""
    given = [flag for flag in ("interrupt_command", "resume_command") if getattr(args, flag)]
    named = " and ".join(f"--{flag.replace('_', '-')}" for flag in given)
    if len(given) == 1:
        other = "--resume-command" if given[0] == "interrupt_command" else "--interrupt-command"
        raise ProbeError(f"{named}: needs {other} too (a case that interrupts the task resumes it)")
    if given and (args.loopback or args.impl):
        where = "--loopback" if args.loopback else "--impl"
        raise ProbeError(f"{named}: for a live server; {where} interrupts the task itself")


def _options(args: argparse.Namespace) -> probe_runner.Options:
    """The probe's options, as the flags give them."""
    known = args.known or ""
    return probe_runner.Options(
        fleet=args.fleet, robot=args.robot, place=args.place[0] if args.place else None,
        more_places=tuple(args.place[1:]) if args.place else (), category=args.category,
        timeout=args.timeout, begin_command=args.begin_command,
        interrupt_command=args.interrupt_command, resume_command=args.resume_command,
        known=probe_cases.KNOWN.get(known, frozenset()), trace=args.trace,
        stubborn_minimum=args.stubborn_minimum, introspection=args.introspection,
        allow_missing=tuple(args.allow_missing), server_wait=args.server_wait,
        ros_args=tuple(args.ros_args), known_missing=probe_cases.KNOWN_MISSING.get(known, frozenset()),
        junit=args.junit, report=args.report, deadline=args.deadline,
    )  # fmt: skip


def _in_process(args: argparse.Namespace, check: Callable[[], list[probe_cases.Case]]) -> int:
    """``dynevent probe --loopback`` (dynevent's own machine as ``dynevent serve`` would run the robot:
    ``--config``, ``--compatibility``, ``--first-seq``) or ``--impl CMD`` (an implementation behind the
    driver protocol, configured the same), on simulated time, with no ROS."""
    try:
        cases = check()
        for flag, given in (("--impl", args.loopback and args.impl), ("--introspection", args.introspection),
                            ("--ros-args", args.ros_args)):  # fmt: skip
            if given:
                mode = "--loopback" if args.loopback else "--impl"
                raise ProbeError(f"{flag}: not with {mode}, which runs in this process, without ROS")
        config, chosen = _in_process_options(args)
        if not args.impl:
            return in_process.probe_in_process(chosen, cases, say, config, write=files.write_text)[0]
        return _implementation(args, chosen, cases, config)
    except DyneventError as exc:
        print(f"dynevent probe: {exc}", file=sys.stderr)
        return 2


def _in_process_options(args: argparse.Namespace) -> tuple[ServeConfig, probe_runner.Options]:
    """The served configuration and the probe's options for ``--loopback`` and ``--impl``: the robot
    starts at the seq wrap unless ``--first-seq`` or the ``--config`` file says where; the places, the
    configured ones (the simulated map takes any place when none is configured); the least stubborn
    period, the configured machine's."""
    first_seq = args.first_seq
    if first_seq is None and args.config is None:
        first_seq = 2**32 - 1
    config = load_config(
        args.config, fleet=args.fleet, robots=[args.robot], compatibility=args.compatibility,
        first_seq=first_seq,
    )  # fmt: skip
    chosen = attrs.evolve(_options(args), stubborn_minimum=machine_config(config).stubborn_minimum)
    if chosen.place is None:
        named = [str(place) for place in config.places or () if place is not None]
        if config.places is None:
            named = list(in_process.PLACES)
        if named:
            chosen = attrs.evolve(chosen, place=named[0], more_places=tuple(named[1:3]))
    return config, chosen


def _implementation(
    args: argparse.Namespace, chosen: probe_runner.Options, cases: list[probe_cases.Case], config: ServeConfig
) -> int:
    """``--impl CMD``: the driver started (given at least the runner's START_TIMEOUT), probed, closed."""
    from dynevent.conformance.vectors.runner import MAX_TIMEOUT, ExternalImplementation
    from dynevent.interrupts import interruptible

    implementation = ExternalImplementation(args.impl, timeout=min(args.timeout, MAX_TIMEOUT))
    try:
        with interruptible():  # Ctrl-C or SIGTERM, however inherited: the driver is ended as it stops
            say(f"implementation: {implementation.name}")
            return in_process.probe_in_process(
                chosen, cases, say, config, write=files.write_text, implementation=implementation
            )[0]
    finally:
        implementation.close()
