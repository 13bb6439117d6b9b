"""The ``dynevent`` command line: it parses, then calls one function, the ``run(args)`` of the command's
own module, ``dynevent.tools.<command>`` (:data:`COMMANDS`), imported only then, so that ``dynevent
--help`` stays quick; a command prints its own output and writes its files through
:mod:`dynevent.files`.  What any command raises of dynevent's errors is one line here, never a
traceback, and Ctrl-C or SIGTERM its exit status."""

from __future__ import annotations

import argparse
import importlib
import io
import os
import sys
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from dynevent import DOCS, __version__
from dynevent.tools.diagram import FORMATS
from dynevent.wire.vocab import Compatibility

if TYPE_CHECKING:
    _Commands = argparse._SubParsersAction[argparse.ArgumentParser]

__all__ = ["COMMANDS", "main"]

_EPILOG = (
    "Exit status: 0 ok, 1 findings or failures (check: violations; explain: the goal is refused; "
    f"vectors: a vector fails), 2 usage or input errors.  Documentation: {DOCS}/cli.md"
)
_DESCRIPTION = (
    "dynevent: the reference implementation of the Open-RMF Dynamic Event protocol.  Start with "
    "`dynevent demo`, a scripted session between a client and a robot's server."
)


def _add_demo_command(commands: _Commands) -> None:
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
    shape.add_argument("--mermaid", action="store_true", help="print it as a Mermaid sequence diagram")
    parser.add_argument("--seed", type=int, default=0, metavar="N", help="seed of delays and the race (0)")


def _add_check_command(commands: _Commands) -> None:
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


def _add_explain_command(commands: _Commands) -> None:
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


def _add_vectors_command(commands: _Commands) -> None:
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


def _add_diagram_command(commands: _Commands) -> None:
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


def _add_record_command(commands: _Commands) -> None:
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


def _add_serve_command(commands: _Commands) -> None:
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


def _add_probe_command(commands: _Commands) -> None:
    parser = commands.add_parser(
        "probe",
        help="test a live Dynamic Event server over ROS 2, case by case, against docs/spec.md",
        description="Point at a fleet and robot on a live ROS 2 graph and run the probe's cases as a "
        "client would (raw goals, the status and begin topics): each case cites the rules it tests and "
        "ends pass, fail (with the D-number when docs/divergences.md records that way of "
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
    for what in ("interrupt", "resume"):
        parser.add_argument(
            f"--{what}-command", metavar="CMD",
            help=f"a command that {what}s the robot's task (R14) and exits 0 once it took effect: with "
            "both, the cases that interrupt the task run (e.g. dynevent task interrupt)",
        )  # fmt: skip
    parser.add_argument(
        "--known", choices=["rmf_ros2"],
        help="count the divergences docs/divergences.md records for rmf_ros2 as known (shown, not failing), "
        "and the cases it cannot reach (begin.seq_wrap) as expected to be missing",
    )  # fmt: skip
    _add_probe_outputs(parser)
    _add_loopback_arguments(parser)


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


def _add_send_command(commands: _Commands) -> None:
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


def _add_task_command(commands: _Commands) -> None:
    parser = commands.add_parser(
        "task",
        help="tell a running dynevent serve what happens to a robot's task: begin, interrupt, resume",
        description="Tell the dynevent serve of a robot what happens to its task: begin a dynamic event "
        "(R3), interrupt the task (R14: a child that would start waits for the resume, R6.3) or resume it "
        "(the robot's parameter interrupted.<robot>, set once the server took it).  ROS 2's own arguments "
        "follow --ros-args.  Exit status: 0 once the serve took it, 1 when it did not, 2 on bad usage or "
        "when no serve of the robot was found.",
    )
    parser.add_argument("what", choices=("begin", "interrupt", "resume"), help="what happens to the task")
    parser.add_argument("--fleet", default="tinyRobot", help="the robot's fleet (default: %(default)s)")
    parser.add_argument("--robot", default="tinyRobot1", help="the robot (default: %(default)s)")
    parser.add_argument("--description", metavar="JSON", help="a begin's description (default: the serve's)")
    parser.add_argument("--timeout", type=float, default=10.0, metavar="SECONDS", help="bound (default 10 s)")


#: The commands that run rclpy, and so take ROS 2's own arguments after ``--ros-args``.
ROS_COMMANDS = frozenset({"serve", "send", "probe", "record", "task"})


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


#: Every command, in the order ``dynevent --help`` lists them, and what adds its flags; each runs as
#: the ``run(args)`` of its own module, ``dynevent.tools.<command>``.
COMMANDS: dict[str, Callable[[_Commands], None]] = {
    "demo": _add_demo_command,
    "check": _add_check_command,
    "explain": _add_explain_command,
    "diagram": _add_diagram_command,
    "vectors": _add_vectors_command,
    "serve": _add_serve_command,
    "send": _add_send_command,
    "probe": _add_probe_command,
    "record": _add_record_command,
    "task": _add_task_command,
}


def _run(args: argparse.Namespace) -> int:
    """The command's one function, imported now: ``dynevent.tools.<command>.run(args)``."""
    return int(importlib.import_module(f"dynevent.tools.{args.command}").run(args))


def _command(argv: Sequence[str] | None) -> int:
    parser: argparse.ArgumentParser = _Parser(prog="dynevent", description=_DESCRIPTION, epilog=_EPILOG)
    parser.add_argument("--version", action="version", version=f"dynevent {__version__}")
    commands = parser.add_subparsers(dest="command")
    for add in COMMANDS.values():
        add(commands)
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
        result = _run(args)
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
