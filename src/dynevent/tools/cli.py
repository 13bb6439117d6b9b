"""The ``dynevent`` command line."""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import io
import os
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from dynevent import DOCS, __version__
from dynevent.tools.diagram import FORMATS
from dynevent.wire.vocab import Compatibility

__all__ = ["main"]

_EPILOG = (
    "Exit status: 0 ok, 1 findings or failures (check: violations; explain: the goal is refused; "
    f"vectors: a vector fails), 2 usage or input errors.  Documentation: {DOCS}/cli.md"
)
_DESCRIPTION = (
    "dynevent: the reference implementation of the Open-RMF Dynamic Event protocol.  Start with "
    "`dynevent demo`, a scripted session between a client and a robot's server."
)


def _lazy(module: str) -> Callable[[argparse.Namespace], int]:
    """The ``_run`` of ``module`` (a dotted name), imported when the command runs: ``--help`` stays quick."""

    def run(args: argparse.Namespace) -> int:
        code: int = importlib.import_module(module)._run(args)
        return code

    return run


def _add_demo_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = commands.add_parser(
        "demo",
        help="run a scripted client/server session for one robot and print its timeline",
        description="Run a scripted session between a client machine and a server machine for one "
        "robot, over the in-process loopback: begin, a NEXT with progress and logs, a clamped "
        "stubborn period held over ticks, a wrong CANCEL rejected by the server, a right CANCEL, "
        "two racing NEXT goals, FINISHED, and a goal after the end.  The same seed prints the same "
        "output.  Exit status: 0.",
    )
    shape = parser.add_mutually_exclusive_group()
    shape.add_argument("--json", action="store_true", help="print one JSON object per timeline event")
    shape.add_argument(
        "--mermaid", action="store_true", help="print the session as a Mermaid sequence diagram"
    )
    parser.add_argument(
        "--seed", type=int, default=0, metavar="N", help="seed of the message delays and the race (0)"
    )
    parser.set_defaults(run=_lazy("dynevent.tools.demo"))


def _add_check_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = commands.add_parser(
        "check",
        help="check an observed trace of one robot, or a rosbag2 recording, against the protocol rules",
        description="Replay TRACE, a JSON-lines record of what was observed on the wire for one robot "
        f"({DOCS}/trace-format.md), against the server machine in observer mode, and report every "
        "protocol violation with its line, its spec rule and what was expected.  TRACE may also be a "
        "rosbag2 recording (a bag directory, or one .mcap or .db3 file; the bags extra): every robot "
        f"in it is judged, each violation at its bag time ({DOCS}/recordings.md).  Exit status: "
        "0 when the trace is clean, 1 when it holds violations, 2 on a usage error or unreadable input "
        "(the message names the file, the line and the field).",
    )
    parser.add_argument(
        "trace", metavar="TRACE", help="the trace file, - for standard input, or a rosbag2 recording"
    )
    parser.add_argument("--json", action="store_true", help="one JSON object per violation, then a summary")
    parser.add_argument(
        "--compatibility", choices=[mode.value for mode in Compatibility],
        default=Compatibility.STANDARD.value,
        help="judge the server as the spec says (default), or as `dynevent serve --compatibility rmf_ros2` "
        "behaves: what is left is where it differs from that emulation (a trace's config record wins)",
    )  # fmt: skip
    parser.set_defaults(run=_lazy("dynevent.tools.check"))


def _add_explain_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = commands.add_parser(
        "explain",
        help="would a robot in this state accept this goal? if not, why, and what to send instead",
        description="Rebuild the server state a DynamicEventStatus message describes and say whether "
        "the goal would be accepted; if not, the reason code, its spec rule, the values, and "
        "the goal to send instead.  Also says what a status message cannot tell.  Exit status: 0 "
        "when the goal is accepted and begins, 1 when it is rejected or aborted at its start, 2 on a "
        "usage error or bad JSON (the message names the argument and the field).",
    )
    parser.add_argument(
        "--status",
        required=True,
        metavar="STATUS_JSON",
        help="the robot's DynamicEventStatus as JSON, e.g. '{\"dynamic_event_seq\": 3, "
        '"dynamic_state": 2, "status": "underway", "id": 8}\'; @FILE reads it from FILE, - from '
        "standard input",
    )
    parser.add_argument(
        "--goal",
        required=True,
        metavar="GOAL_JSON",
        help='the DynamicEvent goal as JSON (ROS field names), e.g. \'{"dynamic_event_seq": 3, '
        '"event_type": 2, "id": 8}\'; @FILE reads it from FILE, - from standard input',
    )
    parser.add_argument(
        "--categories",
        metavar="A,B",
        help="the robot's supported categories, comma-separated (default: unknown; the goal's own "
        "category is taken as supported)",
    )
    parser.add_argument(
        "--compatibility",
        choices=[mode.value for mode in Compatibility],
        default=Compatibility.STANDARD.value,
        help="judge as the spec says (standard, the default) or as rmf_ros2 does (accept, then abort)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(run=_lazy("dynevent.tools.explain_command"))


def _vectors(args: argparse.Namespace) -> int:
    """``dynevent vectors``: run the conformance vectors; 0 all pass, 1 any fails, 2 bad input."""
    from dynevent import files
    from dynevent.conformance import vectors
    from dynevent.errors import FileError
    from dynevent.interrupts import interruptible
    from dynevent.tools._progress import Progress
    from dynevent.wire import _json

    if args.files and not vectors.schema_validation_available():
        print(
            "dynevent vectors: note: jsonschema is not installed, so the files are checked by dynevent's "
            "own reader only; pip install 'dynevent[vectors]' to validate them against the schema",
            file=sys.stderr,
        )
    try:
        loaded = vectors.load_vectors(args.files)
    except vectors.InvalidVector as exc:
        print(f"dynevent vectors: invalid vector file: {exc}", file=sys.stderr)
        return 2
    if not loaded:
        print(f"dynevent vectors: no vector in {', '.join(args.files)}", file=sys.stderr)
        return 2
    chosen = vectors.select_vectors(loaded, args.filter)
    if not chosen:
        print(f"dynevent vectors: no vector matches {' or '.join(args.filter)}", file=sys.stderr)
        return 2
    implementation: vectors.InProcessImplementation | vectors.ExternalImplementation
    try:
        _check_writable("junit", args.junit)
        if args.impl is None:
            implementation = vectors.InProcessImplementation()
        else:
            implementation = vectors.ExternalImplementation(args.impl, timeout=args.timeout)
    except (vectors.ImplementationError, FileError) as exc:
        print(f"dynevent vectors: {exc}", file=sys.stderr)
        return 2
    progress = Progress("dynevent vectors", len(chosen))
    outcomes: list[vectors.Outcome] = []
    began = time.monotonic()
    try:
        with interruptible():  # Ctrl-C or SIGTERM, however inherited: the driver is ended as it stops
            for outcome in vectors.run_vectors(chosen, implementation, max_failures=args.max_failures):
                outcomes.append(outcome)
                if args.json:  # as it is known: a run cut short keeps a line for each vector it ran
                    progress.close()
                    print(_json.dumps(vectors.outcome_record(outcome)), flush=True)
                progress.update(len(outcomes), f"({len(outcomes)} of {len(chosen)}: {outcome.vector.name})")
    finally:
        progress.close()
        implementation.close()
    took = time.monotonic() - began
    if args.junit is not None:
        try:
            files.write_text(args.junit, vectors.junit_xml(outcomes, implementation.name), "--junit")
        except FileError as exc:
            print(f"dynevent vectors: {exc}", file=sys.stderr)
            return 2
    if args.json:
        print(_json.dumps(vectors.summary_record(outcomes, implementation.name, seconds=took)))
    else:
        print(vectors.format_report(outcomes, implementation.name))
        print(vectors.took_line(took))
    return 0 if all(outcome.passed for outcome in outcomes) else 1


def _count(text: str) -> int:
    """``--max-failures``: a whole number above 0."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a number above 0, got {text}")
    return value


def _timeout(text: str) -> float:
    """``--timeout``: a finite number of seconds above 0, at most the vectors' bound."""
    from dynevent.conformance.vectors import MAX_TIMEOUT

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not 0 < value <= MAX_TIMEOUT:  # NaN fails both comparisons
        raise argparse.ArgumentTypeError(f"expected seconds above 0 and at most {MAX_TIMEOUT:g}, got {text}")
    return value


def _add_vectors_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = commands.add_parser(
        "vectors",
        help="run the conformance vectors against an implementation",
        description="Run conformance vectors (the shipped ones, or FILEs) against dynevent in process "
        f"or against COMMAND, a program speaking the driver protocol of {DOCS}/conformance.md.  Exit status: "
        "0 when every vector passes, 1 when one fails or is not run, 2 on a usage or vector-file error or an "
        "implementation that cannot start.",
    )
    parser.add_argument(
        "files", nargs="*", metavar="FILE", help="vector files (default: the shipped vectors)"
    )
    parser.add_argument("--impl", metavar="COMMAND", help="run COMMAND as the implementation under test")
    parser.add_argument(
        "--filter",
        metavar="NAME",
        action="append",
        help="only vectors whose name contains NAME, matches it as a glob, or cite it as a rule (R9.3); "
        "repeatable",
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="one JSON object per vector, printed as it ends, then a summary object",
    )
    parser.add_argument(
        "--timeout",
        type=_timeout,
        default=10.0,
        metavar="SECONDS",
        help="longest wait for one answer, in seconds (10); a driver that does not answer in time is "
        "restarted for the next vector",
    )
    parser.add_argument(
        "--max-failures",
        type=_count,
        metavar="N",
        help="stop after N failed vectors (the rest are reported as not run)",
    )
    parser.add_argument(
        "-x", "--exitfirst", dest="max_failures", action="store_const", const=1, help="--max-failures 1"
    )
    parser.add_argument("--junit", metavar="FILE", help="also write the results to FILE as JUnit XML")
    parser.set_defaults(run=_vectors)


def _diagram(args: argparse.Namespace) -> int:
    from dynevent.tools.diagram import render

    print(render(args.format), end="")
    return 0


def _add_diagram_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = commands.add_parser(
        "diagram",
        help="print the server's phase diagram",
        description="Print the server machine's phase diagram, drawn from "
        "dynevent.server.machine.TRANSITIONS "
        f"(the Mermaid form is the one {DOCS}/spec.md embeds).  Exit status: 0.",
    )
    parser.add_argument(
        "--format", choices=FORMATS, default="mermaid", help="mermaid (the default) or dot (Graphviz)"
    )
    parser.set_defaults(run=_diagram)


def _ros_module(command: str) -> Any:
    """``dynevent.tools.live.<command>`` (over the ROS binding), or None after two lines on standard
    error: what is missing, and how to get it (the setup script ships in the package:
    ``dynevent/ros/setup/setup-ros-env.sh``)."""
    try:
        return importlib.import_module(f"dynevent.tools.live.{command}")
    except ImportError as exc:
        missing = (exc.name or "rclpy").split(".")[0]  # the package to install, not its submodule
        if missing != "rclpy" and importlib.util.find_spec("rclpy") is None:
            missing = "rclpy"  # the root of what is missing, whichever ROS package was imported first
        script = Path(__file__).resolve().parent.parent / "ros" / "setup" / "setup-ros-env.sh"
        print(
            f"dynevent {command}: needs ROS 2 (rclpy, rmf_task_msgs); {missing} is not importable",
            file=sys.stderr,
        )
        out = Path.cwd() / "build" / "ros"
        print(
            f"  get it, into this environment: bash {script} {sys.prefix} {out} && . {out}/env.sh",
            file=sys.stderr,
        )
        return None


def _say(line: str) -> None:
    """Print one whole line at once: the live logs print from several threads."""
    sys.stdout.write(line + "\n")
    sys.stdout.flush()


def _ros_command(command: str, check: Callable[[], Any], run: Callable[[Any, Any], int]) -> int:
    """A ROS command: ``check()`` its own input first (a mistake there needs no ROS to be told), then
    ``run(module, checked)`` with ``dynevent.tools.live.<command>``; a DyneventError is one line,
    exit 2."""
    from dynevent.errors import DyneventError

    try:
        checked = check()
        module = _ros_module(command)
        return 2 if module is None else int(run(module, checked))
    except DyneventError as exc:
        print(f"dynevent {command}: {exc}", file=sys.stderr)
        return 2


def _serve(args: argparse.Namespace) -> int:
    from dynevent.errors import ServeError
    from dynevent.sim.config import load_config

    def check() -> Any:
        if not 0 <= args.grace <= 3600:
            raise ServeError(f"--grace: expected seconds from 0 to 3600 (got {args.grace})")
        _check_writable("report", args.report)
        config = load_config(
            args.config, fleet=args.fleet, robots=args.robots or (), rebegin=args.rebegin,
            first_seq=args.first_seq, compatibility=args.compatibility, shard=args.shard,
        )  # fmt: skip
        _check_writable("trace", args.trace, directory=len(config.served()) > 1)  # a file a robot
        return config

    def run(serve: Any, config: Any) -> int:
        watch = serve.Watch(judge=not args.no_judge, grace=args.grace, report=args.report, trace=args.trace,
                            introspection=args.introspection)  # fmt: skip
        return int(serve.run(config, args.state, args.seconds, _say, watch, args.ros_args))

    return _ros_command("serve", check, run)


def _record(args: argparse.Namespace) -> int:
    from dynevent.errors import RecordError

    def check() -> None:
        if args.seconds is not None and not 0 < args.seconds < 1e9:
            raise RecordError(f"--seconds: expected positive seconds (got {args.seconds})")
        if args.output and os.path.lexists(args.output):  # lexists: a path too long to stat is not there
            raise RecordError(f"--output {args.output}: exists already (a bag is a new directory)")
        if args.all and (args.fleet or args.robot):
            named = "--fleet" if args.fleet else "--robot"
            raise RecordError(f"--all: records every robot of every fleet, so {named} cannot narrow it")
        _check_writable("output", args.output, directory=True)

    def run(record: Any, _: None) -> int:
        options = record.RecordOptions(
            output=args.output, fleets=tuple(args.fleet or ()), robots=tuple(args.robot or ()),
            seconds=args.seconds, ros_args=tuple(args.ros_args),
        )  # fmt: skip
        return int(record.run(options, _say))

    return _ros_command("record", check, run)


def _add_record_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = commands.add_parser(
        "record",
        help="record the Dynamic Event conversations of a live system into a rosbag2 bag (MCAP)",
        description="Subscribe to every Dynamic Event name on the ROS 2 graph (each robot's status and "
        "begin topics, the fleet-wide begin topic, the action's feedback and goal status topics, and "
        "the action's service events where introspection is on) and write each message as it "
        "arrives into an MCAP bag in the rosbag2 layout, which ros2 bag and dynevent check read "
        f"({DOCS}/recordings.md).  Runs until Ctrl-C or --seconds; stops cleanly.  Exit status: 0, "
        "or 2 for a bad option or an output that cannot be written.",
    )
    parser.add_argument(
        "-o", "--output", metavar="DIR", help="the bag directory to create (default dynevent_<date>-<time>)"
    )
    parser.add_argument(
        "--fleet", action="append", metavar="FLEET", help="only this fleet's robots; repeatable"
    )
    parser.add_argument("--robot", action="append", metavar="ROBOT", help="only these robots; repeatable")
    parser.add_argument(
        "--all", action="store_true", help="every robot of every fleet, as they appear (the default)"
    )
    parser.add_argument("--seconds", type=float, metavar="SECONDS", help="stop after this long")
    parser.set_defaults(run=_record)


def _add_serve_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = commands.add_parser(
        "serve",
        help="a Dynamic Event server for a fleet of simulated robots, over ROS 2",
        description="Serve the Dynamic Event protocol for every robot of a fleet in one process, "
        "with simulated child events that do what their descriptions say (every category of the "
        "deployed system, each description checked by its schema and the robots' map and actions: "
        "docs/descriptions.md; go_to_place takes 3 s, reports each second, fails on the place "
        "'nowhere'; perform_action takes 2 s or its duration estimate).  Each robot begins a "
        "dynamic event at start, again after a run ends, and when a DynamicEventDescription naming "
        "it arrives on dynevent/serve/begin.  With --state, every robot's state is kept in a "
        "SQLite file and a restart continues every run.  Prints a live log.  Runs until Ctrl-C.  "
        "Exit status: 0, or 2 for a bad configuration or state file (the file is then left as it "
        "was).",
    )
    parser.add_argument("--fleet", help="the fleet's name (default tinyRobot)")
    parser.add_argument(
        "--robot",
        action="append",
        dest="robots",
        metavar="ROBOT",
        help="a robot's name; repeat for more (default tinyRobot1)",
    )
    parser.add_argument(
        "--config", metavar="FILE", help="a JSON file: fleet, robots, categories, compatibility"
    )
    parser.add_argument("--state", metavar="FILE", help="keep every robot's state in this SQLite file")
    parser.add_argument(
        "--rebegin",
        type=float,
        metavar="SECONDS",
        help="begin a new dynamic event this long after a run ends; 0 never (default 2)",
    )
    parser.add_argument(
        "--first-seq",
        type=int,
        metavar="SEQ",
        help="the seq of each robot's first run (default 1); 4294967295 shows the seq wrap to 0 (R3.2)",
    )
    parser.add_argument(
        "--compatibility",
        choices=[mode.value for mode in Compatibility],
        help="serve as the spec says (standard, the default) or as rmf_ros2 does where they differ",
    )
    parser.add_argument(
        "--shard",
        metavar="K/N",
        help="serve only the robots whose names hash to part K of N: run N processes, 1/N to N/N, "
        "for one fleet (each with its own --state file)",
    )
    parser.add_argument("--seconds", type=float, metavar="SECONDS", help="stop after this long")
    parser.add_argument(
        "--no-judge", action="store_true",
        help="do not judge the clients (by default every goal is judged against docs/spec.md section 22, "
        "a line per finding, and a summary at exit)",
    )  # fmt: skip
    parser.add_argument(
        "--grace", type=float, default=0.5, metavar="SECONDS",
        help="how long a status takes to reach a client, for the judgement (default 0.5)",
    )  # fmt: skip
    parser.add_argument(
        "--report", metavar="FILE", help="write the judgement of the clients as Markdown at exit"
    )
    parser.add_argument(
        "--introspection", action="store_true",
        help="publish the action's service events (ROS 2 introspection, with contents), so that a "
        "recording holds the goals and their answers (docs/recordings.md); on whenever the clients "
        "are judged",
    )  # fmt: skip
    parser.add_argument(
        "--trace", metavar="PATH",
        help="write every step as a trace dynevent check reads: a file for one robot, a directory of "
        "ROBOT.jsonl for several",
    )  # fmt: skip
    parser.set_defaults(run=_serve)


def _send(args: argparse.Namespace) -> int:
    from dynevent.errors import SendError
    from dynevent.tools.send_request import goal_request

    def check() -> tuple[Any, str, str]:
        if not 0 < args.timeout < 1e6:
            raise SendError(f"--timeout: expected positive seconds (got {args.timeout})")
        _check_writable("trace", args.trace)
        return goal_request(args)

    def run(send: Any, goal: tuple[Any, str, str]) -> int:
        event_type, category, description = goal
        options = send.SendOptions(
            fleet=args.fleet, robot=args.robot, event_type=event_type, category=category,
            description=description, stubborn_period=args.stubbornness, timeout=args.timeout,
            trace=args.trace, introspection=args.introspection, wait=args.wait, ros_args=tuple(args.ros_args),
        )  # fmt: skip
        return int(send.run(options, _say))

    return _ros_command("send", check, run)


def _check_writable(flag: str, path: str | None, *, directory: bool = False) -> None:
    """Refuse, before the command's work starts, an output ``--flag PATH`` it could not write
    (:func:`dynevent.files.check_writable`)."""
    from dynevent import files

    if path is not None:
        files.check_writable(path, f"--{flag}", directory=directory)


def _probe(args: argparse.Namespace) -> int:
    from dynevent.conformance.probe import cases as probe_cases
    from dynevent.errors import DyneventError, ProbeError

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
            _check_writable(flag, getattr(args, flag))
        return cases

    if args.list:
        try:
            sys.stdout.write(probe_cases.format_list(check()))
        except DyneventError as exc:
            print(f"dynevent probe: {exc}", file=sys.stderr)
            return 2
        return 0

    def options(options_type: Any) -> Any:
        known = args.known or ""
        return options_type(
            fleet=args.fleet, robot=args.robot, place=args.place[0] if args.place else None,
            more_places=tuple(args.place[1:]) if args.place else (), category=args.category,
            timeout=args.timeout, begin_command=args.begin_command,
            known=probe_cases.KNOWN.get(known, frozenset()), trace=args.trace,
            stubborn_minimum=args.stubborn_minimum, introspection=args.introspection,
            allow_missing=tuple(args.allow_missing), server_wait=args.server_wait,
            ros_args=tuple(args.ros_args), known_missing=probe_cases.KNOWN_MISSING.get(known, frozenset()),
            junit=args.junit, report=args.report, deadline=args.deadline,
        )  # fmt: skip

    if args.loopback or args.impl:
        return _probe_in_process(args, check, options)

    def run(probe: Any, cases: list[probe_cases.Case]) -> int:
        return int(probe.main(options(probe.Options), cases, _say))

    return _ros_command("probe", check, run)


def _probe_in_process(
    args: argparse.Namespace, check: Callable[[], Any], options: Callable[[Any], Any]
) -> int:
    """``dynevent probe --loopback`` (dynevent's own machine as ``dynevent serve`` would run the robot:
    ``--config``, ``--compatibility``, ``--first-seq``) or ``--impl CMD`` (an implementation behind the
    driver protocol, configured the same), on simulated time, with no ROS."""
    from dynevent.conformance.probe import in_process
    from dynevent.errors import DyneventError, ProbeError

    try:
        cases = check()
        for flag, given in (("--impl", args.loopback and args.impl), ("--introspection", args.introspection),
                            ("--ros-args", args.ros_args)):  # fmt: skip
            if given:
                mode = "--loopback" if args.loopback else "--impl"
                raise ProbeError(f"{flag}: not with {mode}, which runs in this process, without ROS")
        config, chosen = _in_process_options(args, options)
        if not args.impl:
            return in_process.probe_in_process(chosen, cases, _say, config)[0]
        return _probe_implementation(args, chosen, cases, config)
    except DyneventError as exc:
        print(f"dynevent probe: {exc}", file=sys.stderr)
        return 2


def _in_process_options(args: argparse.Namespace, options: Callable[[Any], Any]) -> tuple[Any, Any]:
    """The served configuration and the probe's options for ``--loopback`` and ``--impl``: the robot
    starts at the seq wrap unless ``--first-seq`` or the ``--config`` file says where; the places, the
    configured ones (the simulated map takes any place when none is configured); the least stubborn
    period, the configured machine's."""
    import attrs

    from dynevent.conformance.probe import in_process
    from dynevent.conformance.probe import runner as probe_runner
    from dynevent.sim.config import load_config, machine_config

    first_seq = args.first_seq
    if first_seq is None and args.config is None:
        first_seq = 2**32 - 1
    config = load_config(
        args.config, fleet=args.fleet, robots=[args.robot], compatibility=args.compatibility,
        first_seq=first_seq,
    )  # fmt: skip
    chosen = attrs.evolve(
        options(probe_runner.Options), stubborn_minimum=machine_config(config).stubborn_minimum
    )
    if chosen.place is None:
        named = [str(place) for place in config.places or () if place is not None]
        if config.places is None:
            named = list(in_process.PLACES)
        if named:
            chosen = attrs.evolve(chosen, place=named[0], more_places=tuple(named[1:3]))
    return config, chosen


def _probe_implementation(args: argparse.Namespace, chosen: Any, cases: Any, config: Any) -> int:
    """``--impl CMD``: the driver started (given at least the runner's START_TIMEOUT), probed, closed."""
    from dynevent.conformance.probe import in_process
    from dynevent.conformance.vectors.runner import MAX_TIMEOUT, ExternalImplementation
    from dynevent.interrupts import interruptible

    implementation = ExternalImplementation(args.impl, timeout=min(args.timeout, MAX_TIMEOUT))
    try:
        with interruptible():  # Ctrl-C or SIGTERM, however inherited: the driver is ended as it stops
            _say(f"implementation: {implementation.name}")
            return in_process.probe_in_process(chosen, cases, _say, config, implementation=implementation)[0]
    finally:
        implementation.close()


def _add_probe_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = commands.add_parser(
        "probe",
        help="test a live Dynamic Event server over ROS 2, case by case, against docs/spec.md",
        description="Point at a fleet and robot on a live ROS 2 graph and run the probe's cases as a "
        "client would (raw goals, the status and begin topics): each case cites the rules it tests and "
        "ends pass, non-strict, fail (with the D-number when docs/divergences.md records that way of "
        "breaking it), info or missing.  --list prints the cases without ROS; --loopback runs them "
        "without ROS against dynevent's own machine, as dynevent serve would run the robot, and --impl "
        "against an implementation behind the conformance driver protocol.  Exit status: 0 every "
        "case ran and none failed, 1 a case failed, 2 bad usage or no server, 3 a case was not run "
        "(missing) that --allow-missing or --known did not expect.",
    )
    parser.add_argument("--fleet", default="tinyRobot", help="the robot's fleet (default: %(default)s)")
    parser.add_argument("--robot", default="tinyRobot1", help="the robot to probe (default: %(default)s)")
    parser.add_argument("--list", action="store_true", help="print the cases (no ROS needed) and exit")
    parser.add_argument(
        "--cases", nargs="+", default=[], metavar="PATTERN",
        help="run only these: case ids or globs (request.*), sections (cancel), rules (R4.*)",
    )  # fmt: skip
    parser.add_argument(
        "--allow-missing", nargs="+", default=[], metavar="PATTERN",
        help="cases that may be missing (not run) without failing the run, as --cases names them; every "
        "other missing case makes the exit status 3",
    )  # fmt: skip
    parser.add_argument(
        "--place", nargs="+", metavar="PLACE",
        help="places the robot can go to, for the cases that send it somewhere, taken in turn so that a "
        "child does not end at once where the robot stands (default: the go_to_place estimate of the "
        "run's description, when it names one)",
    )  # fmt: skip
    parser.add_argument(
        "--category",
        default="go_to_place",
        help="the category of those children's NEXT (default: %(default)s)",
    )
    parser.add_argument(
        "--timeout", type=float, default=10.0, metavar="SECONDS",
        help="bound on each wait of a case (default: %(default)s); after 3 cases in a row wait it out and "
        "hear nothing, the rest are not run",
    )  # fmt: skip
    parser.add_argument(
        "--deadline", type=float, default=120.0, metavar="SECONDS",
        help="bound on the whole run in real time, once the server is found (default: %(default)s, enough "
        "for every case against the docs' serve; with --loopback or --impl it bounds simulated time too): "
        "no wait goes past it, nothing is asked of the server after it, and the cases left are not run, "
        "with why; the run ends within --server-wait, this, and a few seconds to close",
    )  # fmt: skip
    parser.add_argument(
        "--server-wait", type=float, default=10.0, metavar="SECONDS",
        help="how long to wait for the robot's server to appear on the graph (default: %(default)s)",
    )  # fmt: skip
    parser.add_argument(
        "--stubborn-minimum", type=float, default=2.0, metavar="SECONDS",
        help="the server's least stubborn period (default 2, rmf_ros2's): stubborn.clamp_notice asks for a "
        "quarter of it; 0 when the server applies none",
    )  # fmt: skip
    parser.add_argument(
        "--begin-command", metavar="CMD",
        help="a command that begins a dynamic event for the robot, run when a case needs one and none "
        "is active",
    )  # fmt: skip
    parser.add_argument(
        "--known", choices=["rmf_ros2"],
        help="count the divergences docs/divergences.md records for rmf_ros2 as known (shown, not failing), "
        "and the cases it cannot reach (begin.seq_wrap) as expected to be missing",
    )  # fmt: skip
    _add_probe_outputs(parser)
    _add_loopback_arguments(parser)
    parser.set_defaults(run=_probe)


def _add_probe_outputs(parser: argparse.ArgumentParser) -> None:
    """What probe writes beside its terminal report, and what it publishes of its own goals."""
    parser.add_argument("--junit", metavar="FILE", help="write the findings as JUnit XML")
    parser.add_argument(
        "--report", metavar="FILE",
        help="write a report a person reads: per case the rules, the verdict, what was sent and seen "
        "(HTML when FILE ends in .html, else Markdown)",
    )  # fmt: skip
    parser.add_argument(
        "--trace", metavar="FILE",
        help="write every message sent and seen, as a trace dynevent check reads",
    )  # fmt: skip
    parser.add_argument(
        "--introspection", action="store_true",
        help="publish the probe's action service events (ROS 2 introspection, with contents), so that a "
        "recording holds its goals and their answers (docs/recordings.md)",
    )  # fmt: skip


def _add_loopback_arguments(parser: argparse.ArgumentParser) -> None:
    """probe's ``--loopback`` and what configures the server it runs in process."""
    loopback = parser.add_argument_group("in process, without ROS")
    loopback.add_argument(
        "--loopback", action="store_true",
        help="probe dynevent's own machine in this process, as dynevent serve runs the robot, on simulated "
        "time (every case in well under a second; no ROS needed); --place defaults to the configured "
        "places, or pantry and lounge",
    )  # fmt: skip
    loopback.add_argument(
        "--impl", metavar="CMD",
        help="probe an implementation behind the conformance driver protocol (as dynevent vectors --impl "
        "runs it), configured as dynevent serve would configure the machine, on simulated time; no ROS",
    )  # fmt: skip
    loopback.add_argument("--config", metavar="FILE", help="with --loopback or --impl: serve's --config file")
    loopback.add_argument(
        "--first-seq", type=int, metavar="SEQ",
        help="with --loopback or --impl: the seq of the robot's first run (default: the --config file's, "
        "else 4294967295, so that the next run shows the seq wrap to 0 and begin.seq_wrap runs)",
    )  # fmt: skip
    loopback.add_argument(
        "--compatibility", choices=[mode.value for mode in Compatibility],
        help="with --loopback or --impl: the mode serve runs in (default: the --config file's, else "
        "standard)",
    )  # fmt: skip


def _add_send_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = commands.add_parser(
        "send",
        help="send one Dynamic Event goal to a robot over ROS 2 and print what becomes of it",
        description="Send one goal (NEXT, CANCEL or FINISHED) to a robot's Dynamic Event server, with "
        "the seq and id its status implies; print the feedback as it arrives and the outcome; explain "
        "a refusal.  Ctrl-C (or SIGTERM) while the goal is open cancels it and waits, at most 10 s, for "
        "its answer.  ROS 2's own arguments follow --ros-args.  Exit status: 0 when the goal succeeded, "
        "1 when it did not, 2 on bad usage or when no server or status was found, 130 (143) after "
        "Ctrl-C (SIGTERM).",
    )
    parser.add_argument("--fleet", default="tinyRobot", help="the robot's fleet (default: %(default)s)")
    parser.add_argument("--robot", default="tinyRobot1", help="the robot to send to (default: %(default)s)")
    parser.add_argument(
        "--wait", action="store_true",
        help="wait for the robot's server up to --timeout even when the graph shows other robots' servers "
        "(by default send stops after 3 s then, naming the servers it sees)",
    )  # fmt: skip
    parser.add_argument("--place", nargs="+", metavar="PLACE", help='NEXT go_to_place {"one_of": [PLACE...]}')
    parser.add_argument("--cancel", action="store_true", help="CANCEL the running event")
    parser.add_argument("--end", action="store_true", help="FINISHED: the dynamic event is over")
    parser.add_argument(
        "--file", metavar="FILE", help='NEXT from a JSON file {"category": ..., "description": ...}'
    )
    parser.add_argument(
        "--description",
        metavar="JSON",
        help='NEXT with this description: JSON text, or @FILE for a file\'s (e.g. 3, \'{"waypoint": "A"}\', '
        '\'{"category": "wave", "description": {}}\' with --category perform_action)',
    )
    parser.add_argument(
        "--category",
        default="go_to_place",
        help="the category of --description (default go_to_place; the field's categories are "
        "checked here first as the server checks them: docs/descriptions.md)",
    )
    parser.add_argument(
        "--stubbornness",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="stubborn period after a NEXT's event (default 0: none)",
    )
    parser.add_argument(
        "--timeout",
        type=float,
        default=60.0,
        metavar="SECONDS",
        help="bound on the whole exchange (default 60)",
    )
    parser.add_argument(
        "--trace",
        metavar="FILE",
        help="write every message sent and received as a trace dynevent check reads",
    )
    parser.add_argument(
        "--introspection", action="store_true",
        help="publish the action's service events (ROS 2 introspection, with contents), so that a "
        "recording holds the goals and their answers (docs/recordings.md)",
    )  # fmt: skip
    parser.set_defaults(run=_send)


#: The commands that run rclpy, and so take ROS 2's own arguments after ``--ros-args``.
ROS_COMMANDS = frozenset({"serve", "send", "probe", "record"})


def split_ros_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """The command line without its ROS arguments, and those: ``--ros-args`` and what follows it, up to
    a ``--`` that ends them (ROS 2's convention: ``dynevent send --place A --ros-args -r __ns:=/x``)."""
    if "--ros-args" not in argv:
        return argv, []
    start = argv.index("--ros-args")
    end = argv.index("--", start) if "--" in argv[start:] else len(argv)
    return argv[:start] + argv[end + 1 :], argv[start:end]


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``dynevent`` command; return its exit code.  A reader of standard output that goes away
    (``| head``) ends any command quietly with 141, whether its output is buffered or not."""
    try:
        try:
            return _command(argv)
        finally:  # what is still buffered goes now, where a reader gone is answered quietly, not at exit
            sys.stdout.flush()
    except BrokenPipeError:
        return quiet_broken_pipe()


class _Parser(argparse.ArgumentParser):
    """argparse's parser, whose help and usage written to a reader that went away stop the command as
    any other output does (141): Python 3.11's argparse ignores a write that fails, 3.10's does not."""

    def _print_message(self, message: str, file: Any = None) -> None:
        if message:
            (file or sys.stderr).write(message)


def _command(argv: Sequence[str] | None) -> int:
    parser: argparse.ArgumentParser = _Parser(prog="dynevent", description=_DESCRIPTION, epilog=_EPILOG)
    parser.add_argument("--version", action="version", version=f"dynevent {__version__}")
    commands = parser.add_subparsers(dest="command")
    _add_demo_command(commands)
    _add_check_command(commands)
    _add_explain_command(commands)
    _add_diagram_command(commands)
    _add_vectors_command(commands)
    _add_serve_command(commands)
    _add_send_command(commands)
    _add_probe_command(commands)
    _add_record_command(commands)
    for stream in (
        sys.stdout,
        sys.stderr,
    ):  # text another program sent (a lone surrogate) is escaped, not fatal
        if isinstance(stream, io.TextIOWrapper):
            stream.reconfigure(errors="backslashreplace")
    argv, ros_args = split_ros_args(sys.argv[1:] if argv is None else list(argv))
    args = parser.parse_args(argv)
    args.ros_args = ros_args
    if ros_args and args.command not in ROS_COMMANDS:
        parser.error(
            f"--ros-args is for the ROS 2 commands ({', '.join(sorted(ROS_COMMANDS))}), not {args.command}"
        )
    if args.command is None:  # bare `dynevent`: what it can do, not a run of one of its commands
        parser.print_help()
        return 0
    from dynevent.errors import DyneventError
    from dynevent.interrupts import Interrupted

    try:
        result: int = args.run(args)
    except KeyboardInterrupt:
        return 130  # Ctrl-C: the command stops, without a traceback
    except Interrupted as stop:  # a command that held something closed it as this passed
        return 128 + stop.signal
    except DyneventError as exc:  # what a command did not name itself is still one line, never a traceback
        print(f"dynevent {args.command}: {exc}", file=sys.stderr)
        return 2
    return result


def quiet_broken_pipe() -> int:
    """The reader of standard output went away (``| head``): stop quietly, as a shell's tools do."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())  # the interpreter's final flush then has nowhere to fail
    return 141
