"""The ``dynevent`` command, run as a subprocess: every subcommand, ``--help``, exit codes, docs/cli.md.

docs/cli.md's sessions run in tests/project/test_docs_examples.py, with every page's
(``DYNEVENT_UPDATE_DOCS=1`` rewrites them from the commands; then review the diff).
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from dynevent.tools import cli
from dynevent.tools.diagram import render
from support.doc_sessions import sessions

ROOT = Path(__file__).resolve().parents[2]
CLI_DOC = ROOT / "docs" / "cli.md"
SUBCOMMANDS = ("demo", "check", "explain", "diagram", "vectors", "serve", "send", "probe", "record")
RUNNING = '{"dynamic_event_seq": 3, "dynamic_state": 2, "status": "underway", "id": 8}'


def dynevent(*args: str, stdin: str | None = None) -> subprocess.CompletedProcess[str]:
    """Run ``python -m dynevent ARGS`` from the repository's root."""
    return subprocess.run(
        [sys.executable, "-m", "dynevent", *args],
        input=stdin,
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,
        check=False,
    )


# --------------------------------------------------------------------------- every subcommand


@pytest.mark.parametrize("command", SUBCOMMANDS)
def test_help_of_every_subcommand_documents_the_exit_status(command: str) -> None:
    done = dynevent(command, "--help")
    assert done.returncode == 0, done.stderr
    assert f"usage: dynevent {command}" in done.stdout
    assert "Exit status" in " ".join(done.stdout.split())


def test_help_lists_the_subcommands_and_exit_codes() -> None:
    done = dynevent("--help")
    assert done.returncode == 0
    for command in SUBCOMMANDS:
        assert command in done.stdout
    assert "2 usage or input errors" in " ".join(done.stdout.split())


def test_no_arguments_print_the_help() -> None:
    plain, helped = dynevent(), dynevent("--help")
    assert plain.returncode == helped.returncode == 0
    assert plain.stdout == helped.stdout and plain.stderr == ""
    assert "race condition" not in plain.stdout  # the demo did not run


def test_demo_is_byte_identical_for_a_seed_and_json_lines() -> None:
    first, second = dynevent("demo", "--seed", "11"), dynevent("demo", "--seed", "11")
    assert first.stdout == second.stdout and first.returncode == 0
    lines = dynevent("demo", "--json", "--seed", "11").stdout.splitlines()
    records = [json.loads(line) for line in lines]
    assert {"step", "time", "direction", "kind", "summary", "decision", "record"} <= set(records[0])
    decisions = " ".join(record["decision"] for record in records)
    for expected in (
        "rejected: cancel_id_mismatch",
        "race condition",
        "rejected: inactive",
        "stubborn_clamped",
    ):
        assert expected in decisions


def test_check_exit_codes_and_stdin() -> None:
    clean = dynevent("check", "docs/examples/clean-trace.jsonl")
    assert clean.returncode == 0 and "no violations" in clean.stdout
    text = (ROOT / "docs" / "examples" / "rmf_ros2-trace.jsonl").read_text(encoding="utf-8")
    flagged = dynevent("check", "-", stdin=text)
    assert flagged.returncode == 1 and "<stdin>:" in flagged.stdout


@pytest.mark.parametrize(
    ("args", "stdin", "expected"),
    [
        (("check", "no/such/trace.jsonl"), None, "'no/such/trace.jsonl': cannot be opened: No such"),
        (("check", "-"), '{"time": 1, "type": "goal"}\n', "<stdin>:1: goal: missing field"),
        (("check", "-"), "not json\n", "<stdin>:1: $: not valid JSON"),
        (("check", "-"), '{"time": true, "type": "status", "message": {}}', "<stdin>:1: time:"),
        (("explain", "--status", "{", "--goal", "{}"), None, "--status: DynamicEventStatus: not valid JSON"),
        (
            ("explain", "--status", "{}", "--goal", '{"id": "x"}'),
            None,
            "--goal: Goal.id: expected an integer",
        ),
        (
            ("explain", "--status", "{}", "--goal", "{}", "--categories", "a,,b"),
            None,
            "--categories: an empty",
        ),
        (("explain", "--status", "{}"), None, "the following arguments are required: --goal"),
        (("demo", "--seed", "x"), None, "invalid int value"),
        (("diagram", "--format", "svg"), None, "invalid choice"),
        (("nonsense",), None, "invalid choice"),
    ],
)
def test_bad_input_exits_2_without_a_traceback(
    args: tuple[str, ...], stdin: str | None, expected: str
) -> None:
    done = dynevent(*args, stdin=stdin)
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert expected in done.stderr
    assert "Traceback" not in done.stderr + done.stdout


def test_explain_exit_codes() -> None:
    accepted = dynevent(
        "explain", "--status", RUNNING, "--goal", '{"dynamic_event_seq": 3, "event_type": 2, "id": 8}'
    )
    assert accepted.returncode == 0 and "verdict:  accepted" in accepted.stdout
    refused = dynevent(
        "explain", "--json", "--status", RUNNING, "--goal", '{"dynamic_event_seq": 3, "event_type": 1}'
    )
    assert refused.returncode == 1
    assert json.loads(refused.stdout)["reason"] == "busy"


def test_explain_reads_json_from_a_file_or_standard_input(tmp_path: Path) -> None:
    goal = '{"dynamic_event_seq": 3, "event_type": 2, "id": 8}'
    inline = dynevent("explain", "--status", RUNNING, "--goal", goal)
    (tmp_path / "status.json").write_text(RUNNING, encoding="utf-8")
    from_file = dynevent("explain", "--status", f"@{tmp_path / 'status.json'}", "--goal", "-", stdin=goal)
    assert (
        (from_file.returncode, from_file.stdout) == (inline.returncode, inline.stdout) == (0, inline.stdout)
    )
    both = dynevent("explain", "--status", "-", "--goal", "-", stdin=RUNNING)
    assert both.returncode == 2 and "--goal: standard input is already read for --status" in both.stderr
    missing = dynevent("explain", "--status", f"@{tmp_path / 'nothing.json'}", "--goal", goal)
    assert (
        missing.returncode == 2
        and "--status: " in missing.stderr
        and "cannot be opened: No such file or directory" in missing.stderr
        and "nothing.json" in missing.stderr
    )
    (tmp_path / "latin.json").write_bytes(b'{"status": "caf\xe9"}')
    latin = dynevent("explain", "--status", f"@{tmp_path / 'latin.json'}", "--goal", goal)
    assert latin.returncode == 2 and "is not UTF-8 (byte 15)" in latin.stderr
    assert "Traceback" not in missing.stderr + latin.stderr + both.stderr


def test_diagram_prints_what_the_spec_embeds() -> None:
    assert dynevent("diagram").stdout == render("mermaid")
    assert dynevent("diagram", "--format", "dot").stdout == render("dot")


def test_main_in_process_returns_the_exit_code(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["diagram"]) == 0
    assert capsys.readouterr().out == render("mermaid")
    assert cli.main(["check", str(ROOT / "docs" / "examples" / "rmf_ros2-trace.jsonl")]) == 1


# --------------------------------------------------------------------------- docs/cli.md
# (its sessions run in tests/project/test_docs_examples.py, as every page's do)


def test_cli_doc_covers_every_subcommand() -> None:
    commands = [command for pairs in sessions(CLI_DOC.read_text(encoding="utf-8")) for command, _ in pairs]
    for sub in ("demo", "check", "explain", "diagram", "vectors"):
        assert any(command.startswith(f"dynevent {sub}") for command in commands), sub


@pytest.mark.parametrize("buffered", [True, False], ids=["buffered", "PYTHONUNBUFFERED"])
@pytest.mark.parametrize(
    "args",
    [["demo"], ["diagram"], ["vectors"], ["check", "docs/examples/clean-trace.jsonl"], ["probe", "--list"]],
    ids=lambda args: args[0],
)
def test_a_reader_that_goes_away_stops_the_command_quietly(args: list[str], buffered: bool) -> None:
    """``dynevent ... | head``: a closed standard output is no traceback, whether the output is
    buffered (a fresh terminal) or not (``PYTHONUNBUFFERED``, as some CI sets it)."""
    status, error = _without_reader(args, buffered)
    assert status == 141, error
    assert "Traceback" not in error and error == ""


@pytest.mark.parametrize("buffered", [True, False], ids=["buffered", "PYTHONUNBUFFERED"])
def test_help_to_a_reader_that_goes_away_is_quiet(buffered: bool) -> None:
    status, error = _without_reader(["--help"], buffered)
    assert error == ""
    # on every Python: its help is output like any other (3.11's argparse alone would ignore the failed
    # write of unbuffered help, and end 0)
    assert status == 141


def _without_reader(args: list[str], buffered: bool) -> tuple[int, str]:
    """``dynevent ARGS`` whose standard output's reader is gone before the first line: its exit status
    and standard error."""
    environment = {name: value for name, value in os.environ.items() if name != "PYTHONUNBUFFERED"}
    if not buffered:
        environment["PYTHONUNBUFFERED"] = "1"
    process = subprocess.Popen(
        [sys.executable, "-m", "dynevent", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=ROOT,
        env=environment,
        text=True,
    )
    assert process.stdout is not None
    process.stdout.close()
    _, error = process.communicate(timeout=60)
    return process.returncode, error


def test_the_driver_stops_quietly_when_its_runner_goes_away() -> None:
    process = subprocess.Popen(
        [sys.executable, "-m", "dynevent.conformance.vectors.driver"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=ROOT,
        text=True,
    )
    assert process.stdin is not None and process.stdout is not None
    process.stdout.close()
    _, error = process.communicate('{"op": "bogus"}\n' * 50, timeout=60)
    assert process.returncode == 141, error
    assert "Traceback" not in error


def test_an_empty_trace_or_vector_file_says_nothing_was_checked(tmp_path: Path) -> None:
    trace = tmp_path / "empty.jsonl"
    trace.write_text("# only a comment\n\n", encoding="utf-8")
    checked = dynevent("check", str(trace))
    assert checked.returncode == 2 and "nothing to check" in checked.stderr and checked.stdout == ""
    empty = tmp_path / "none.json"
    empty.write_text('{"vectors": []}', encoding="utf-8")
    ran = dynevent("vectors", str(empty))
    assert ran.returncode == 2 and f"no vector in {empty}" in ran.stderr


def test_the_testing_kit_without_hypothesis_names_the_extra() -> None:
    blocked = (
        "import sys; sys.modules['hypothesis'] = None\n"
        "try:\n    import dynevent.testing\n"
        "except ModuleNotFoundError as exc:\n    print(exc)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", blocked], capture_output=True, text=True, cwd=ROOT, timeout=60, check=False
    )
    assert done.returncode == 0, done.stderr
    assert "pip install 'dynevent[testing]'" in done.stdout


def test_help_imports_no_protocol_module() -> None:
    """``dynevent --help`` stays quick: the command line imports a command's module only to run it."""
    probe = (
        "import sys; from dynevent.tools import cli\n"
        "try:\n    cli.main(['--help'])\nexcept SystemExit:\n    pass\n"
        "heavy = sorted(m for m in sys.modules if m.startswith(('dynevent.server', 'dynevent.client', "
        "'dynevent.conformance', 'dynevent.bags', 'dynevent.sim', 'dynevent.tools.check', "
        "'dynevent.tools.demo', 'dynevent.tools.explain', 'dynevent.tools.vectors', 'dynevent.tools.serve', "
        "'dynevent.tools.send', 'dynevent.tools.probe', 'dynevent.tools.record', 'dynevent.tools.live')))\n"
        "print('HEAVY', heavy, 'attrs' in sys.modules)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.stdout.strip().endswith("HEAVY [] False"), done.stdout[-300:] + done.stderr


# --------------------------------------------------------------------------- serve and send without ROS


def _without_ros(*args: str, blocked: str = "rclpy") -> subprocess.CompletedProcess[str]:
    """The command line in a Python where ``blocked`` cannot be imported (whatever this one has)."""
    launcher = (
        f"import sys; sys.modules[{blocked!r}] = None; "
        "from dynevent.tools.cli import main; sys.exit(main(sys.argv[1:]))"
    )
    return subprocess.run(
        [sys.executable, "-c", launcher, *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,
        check=False,
    )


def test_the_ros_package_imports_without_ros_and_its_names_say_what_is_missing() -> None:
    """``import dynevent.ros`` is lazy, as the root package is: without rclpy it imports, and a name
    that needs ROS 2 raises ImportError saying what is missing and how to get it."""
    code = (
        "import sys; sys.modules['rclpy'] = None\n"
        "import dynevent.ros\n"
        "assert 'RobotClient' in dir(dynevent.ros)\n"
        "try:\n    dynevent.ros.RobotClient\nexcept ImportError as exc:\n    print(exc)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 0, done.stderr
    expected = "dynevent.ros.RobotClient needs ROS 2 (rclpy) and the rmf_task_msgs"
    assert done.stdout.startswith(expected), done.stdout
    assert "setup-ros-env.sh" in done.stdout


@pytest.mark.parametrize(
    ("args", "problem"),
    [
        (
            ["send", "--cancel", "--end"],
            "dynevent send: give exactly one of --place, --cancel, --end, --file, --description",
        ),
        (
            ["send", "--file", "no/such.json"],
            "dynevent send: --file 'no/such.json': cannot be opened: No such file",
        ),
        (
            ["send", "--description", "{nope"],
            "dynevent send: --description: not JSON dynevent reads: not valid JSON",
        ),
        (
            ["send", "--description", "@no/such.json"],
            "dynevent send: --description 'no/such.json': cannot be opened: No such file",
        ),
        (
            ["serve", "--config", "tests/data/serve-bad-places.json"],
            "dynevent serve: Robot.places: waypoint 1: a name",
        ),
        (["send", "--end", "--timeout", "0"], "dynevent send: --timeout: expected positive seconds"),
        (["serve", "--shard", "3/2"], "dynevent serve: --shard '3/2': expected K/N"),
        (["probe", "--cases", "nothing"], "dynevent probe: --cases nothing: no case matches"),
        (["probe", "--timeout", "0"], "dynevent probe: --timeout: expected positive seconds"),
        (
            ["probe", "--junit", "no/such/dir/probe.xml"],
            "dynevent probe: --junit 'no/such/dir/probe.xml': cannot be written: No such file or directory",
        ),
        (["serve", "--robot", "bad name"], "dynevent serve:"),
        (["serve", "--first-seq", "-1"], "dynevent serve: --first-seq: expected a seq from 0 to 4294967295"),
        (
            ["probe", "--stubborn-minimum", "nan"],
            "dynevent probe: --stubborn-minimum: expected seconds from 0",
        ),
        (["record", "--seconds", "0"], "dynevent record: --seconds: expected positive seconds"),
        (["record", "-o", "."], "dynevent record: --output .: exists already"),
        (["record", "--all", "--robot", "r1"], "dynevent record: --all: records every robot of every fleet"),
        (
            ["record", "-o", "no/such/dir/bag"],
            "dynevent record: --output 'no/such/dir/bag': cannot be written: No such file or directory",
        ),
        (
            ["send", "--end", "--trace", "no/such/dir/t"],
            "dynevent send: --trace 'no/such/dir/t': cannot be written: No such file or directory",
        ),
        (["task", "interrupt", "--timeout", "-1"], "dynevent task: --timeout: expected positive seconds"),
        (["task", "resume", "--description", "{}"], "dynevent task: --description: only a begin takes one"),
        (["task", "begin", "--description", "{nope"], "dynevent task: --description: not JSON"),
        (
            ["probe", "--interrupt-command", "true"],
            "dynevent probe: --interrupt-command: needs --resume-command too",
        ),
        (
            ["probe", "--loopback", "--interrupt-command", "true", "--resume-command", "true"],
            "dynevent probe: --interrupt-command and --resume-command: for a live server; --loopback",
        ),
    ],
)
def test_serve_and_send_check_their_own_input_before_they_need_ros(args: list[str], problem: str) -> None:
    done = _without_ros(*args)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.startswith(problem), done.stderr
    assert "needs ROS" not in done.stderr and "Traceback" not in done.stderr


@pytest.mark.parametrize("blocked", ["rclpy", "rmf_task_msgs"])
@pytest.mark.parametrize(
    "args",
    [
        ["send", "--end"],
        ["serve", "--seconds", "1"],
        ["probe"],
        ["record", "--seconds", "1"],
        ["task", "begin"],
    ],
)
def test_without_ros_serve_and_send_say_what_is_missing_and_how_to_get_it(
    args: list[str], blocked: str
) -> None:
    """Two lines: the package that is missing, and the command that builds it (a script in the package)."""
    if blocked != "rclpy" and importlib.util.find_spec("rclpy") is None:
        pytest.skip("rclpy is not here either: it is the package reported missing")
    done = _without_ros(*args, blocked=blocked)
    assert done.returncode == 2 and done.stdout == ""
    lines = done.stderr.splitlines()
    assert len(lines) == 2, done.stderr
    assert lines[0] == f"dynevent {args[0]}: needs ROS 2 (rclpy, rmf_task_msgs); {blocked} is not importable"
    script = Path(lines[1].split("bash ", 1)[1].split(" ", 1)[0])
    assert script.is_file() and script.name == "setup-ros-env.sh"
    assert script.is_relative_to(Path(dynevent_package_dir()))  # shipped in the package, so in the wheel


def dynevent_package_dir() -> str:
    import dynevent

    return str(Path(dynevent.__file__).parent)


def test_probe_lists_its_cases_without_ros() -> None:
    done = _without_ros("probe", "--list", "--cases", "R4.2")
    assert done.returncode == 0 and done.stderr == ""
    # the stale and future seq with a FINISHED, a NEXT and a CANCEL, and the wrap
    assert done.stdout.splitlines()[-1] == "7 case(s)"
    assert done.stdout.startswith("request.seq_stale")


def test_every_option_of_the_commands_has_help_that_names_its_default() -> None:
    """ROS 2's command-line manners: every option says what it is, and what it is when not given."""
    import argparse

    from dynevent.tools import cli

    parser = argparse.ArgumentParser()
    commands = parser.add_subparsers()
    for add in (cli._add_serve_command, cli._add_send_command, cli._add_probe_command,
                cli._add_record_command, cli._add_check_command):  # fmt: skip
        add(commands)
    silent = []
    for name, sub in commands.choices.items():
        for action in sub._actions:
            text = action.help or ""
            defaulted = action.default not in (None, False, [], argparse.SUPPRESS)
            if not text or (defaulted and "default" not in text):
                silent.append(f"{name} {'/'.join(action.option_strings) or action.dest}")
    assert silent == []


def test_ros_arguments_are_split_off_as_ros_2_programs_take_them() -> None:
    from dynevent.tools.cli import split_ros_args

    assert split_ros_args(["send", "--end"]) == (["send", "--end"], [])
    assert split_ros_args(["send", "--end", "--ros-args", "-r", "__ns:=/x", "--log-level", "debug"]) == (
        ["send", "--end"], ["--ros-args", "-r", "__ns:=/x", "--log-level", "debug"],
    )  # fmt: skip
    assert split_ros_args(["send", "--ros-args", "-r", "__ns:=/x", "--", "--end"]) == (
        ["send", "--end"], ["--ros-args", "-r", "__ns:=/x"],
    )  # fmt: skip
