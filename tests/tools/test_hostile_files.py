"""The command lines' files and paths, hostile or careless: each is one line and exit 2, never a wait
or a traceback.

Every flag that reads a file is given a FIFO (which would block a plain ``open`` for ever), a
directory, a device, a path too long for the system, a missing file, a file too deep to parse, and
one that is not UTF-8; every flag that writes one is given a path too long, a directory, a path in
no such folder and one it has no permission to write.  Each
command is a real subprocess, bounded by a deadline far above what a refusal takes: a hang fails it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from dynevent import files
from dynevent.errors import FileError, shown_path

ROOT = Path(__file__).resolve().parents[2]
LONG = "x" * 5_000  # past every file system's name limit (255) and PATH_MAX (4,096)


def dynevent(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "dynevent", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,  # a FIFO opened as a plain file would hold the command for ever
        check=False,
        stdin=subprocess.DEVNULL,
    )


@pytest.fixture(scope="module")
def hostile(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """Paths of every kind a careless or hostile user gives, by what they are."""
    folder = tmp_path_factory.mktemp("hostile")
    fifo = folder / "fifo"
    os.mkfifo(fifo)
    deep = folder / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000, encoding="utf-8")
    latin = folder / "latin.json"
    latin.write_bytes(b'{"category": "go_to_place", "description": "caf\xe9"}')
    return {
        "a FIFO": str(fifo),
        "a directory": str(folder),
        "a character device": "/dev/zero",
        "too long": LONG,
        "missing": str(folder / "missing.json"),
        "too deep": str(deep),
        "not UTF-8": str(latin),
    }


#: What each kind of path is said to be.
SAID = {
    "a FIFO": "is a FIFO, not a regular file",
    "a directory": "is a directory, not a regular file",
    "a character device": "is a character device, not a regular file",
    "too long": "File name too long",
    "missing": "No such file or directory",
    "too deep": "nested deeper than 64 levels",
    "not UTF-8": "not UTF-8",
}

#: The commands that read a file: the flags, with the file's path put where ``{}`` is.
READERS: dict[str, Callable[[str], list[str]]] = {
    "send --file": lambda path: ["send", "--file", path],
    "send --description @FILE": lambda path: ["send", "--description", "@" + path],
    "serve --config": lambda path: ["serve", "--config", path],
    "explain --goal @FILE": lambda path: ["explain", "--status", "{}", "--goal", "@" + path],
    "vectors FILE": lambda path: ["vectors", path],
}
#: Those whose reading is not JSON (a trace is JSON lines, read as they come).
STREAMED = {"check TRACE": lambda path: ["check", path]}


def _one_line(done: subprocess.CompletedProcess[str]) -> str:
    assert done.returncode == 2, (done.returncode, done.stderr[-2_000:])
    assert "Traceback" not in done.stderr, done.stderr[-2_000:]
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr[-2_000:]
    return lines[0]


@pytest.mark.parametrize("kind", list(SAID))
@pytest.mark.parametrize("reader", list(READERS))
def test_a_file_flag_names_what_it_cannot_read_in_one_line(
    reader: str, kind: str, hostile: dict[str, str]
) -> None:
    line = _one_line(dynevent(*READERS[reader](hostile[kind])))
    assert SAID[kind] in line or (kind == "not UTF-8" and "UTF-8" in line), line


# (a directory is a bag for check: tests/bags/test_bags.py)
@pytest.mark.parametrize("kind", ["a FIFO", "a character device", "too long", "missing"])
def test_check_names_a_trace_it_cannot_read_in_one_line(kind: str, hostile: dict[str, str]) -> None:
    line = _one_line(dynevent(*STREAMED["check TRACE"](hostile[kind])))
    assert SAID[kind] in line, line


#: The commands that write a file: (the command, its flag, its arguments with the path given); each
#: refuses a path before its work starts, the ROS commands without ROS.
WRITERS: dict[str, tuple[str, str, Callable[[str], list[str]]]] = {
    "vectors --junit": ("vectors", "--junit", lambda path: ["vectors", "--junit", path]),
    "probe --junit": ("probe", "--junit", lambda path: ["probe", "--junit", path]),
    "probe --report": ("probe", "--report", lambda path: ["probe", "--report", path]),
    "probe --trace": ("probe", "--trace", lambda path: ["probe", "--trace", path]),
    "probe --list --junit": ("probe", "--junit", lambda path: ["probe", "--list", "--junit", path]),
    "probe --loopback --report": (
        "probe", "--report", lambda path: ["probe", "--loopback", "--report", path]
    ),
    "send --trace": ("send", "--trace", lambda path: ["send", "--place", "A", "--trace", path]),
    "serve --report": ("serve", "--report", lambda path: ["serve", "--report", path]),
    "serve --trace": ("serve", "--trace", lambda path: ["serve", "--trace", path]),
    "serve --trace, a directory for two robots": (
        "serve", "--trace", lambda path: ["serve", "--robot", "a", "--robot", "b", "--trace", path]
    ),
    "record --output": ("record", "--output", lambda path: ["record", "--output", path]),
}  # fmt: skip


@pytest.fixture(scope="module")
def unwritable(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """Output paths a command cannot write, by what they are."""
    folder = tmp_path_factory.mktemp("unwritable")
    if os.geteuid() == 0:  # root writes through a folder's permissions, not into /sys
        forbidden = "/sys/dynevent-output"
    else:
        closed = folder / "closed"
        closed.mkdir(mode=0o500)
        forbidden = str(closed / "output")
    return {
        "too long": LONG,
        "a directory": str(folder),
        "in no such folder": str(folder / "missing" / "output"),
        "without permission": forbidden,
    }


#: What each kind of output path is said to be (after "cannot be written: ").
UNWRITABLE = {
    "too long": ("File name too long",),
    "a directory": ("Is a directory",),
    "in no such folder": ("No such file or directory",),
    "without permission": ("Permission denied", "Operation not permitted"),
}


@pytest.mark.parametrize(
    ("writer", "kind"),
    [
        (writer, kind)
        for writer in WRITERS
        for kind in UNWRITABLE
        if not (writer.endswith("two robots") and kind == "a directory")  # where their traces go
    ],
)
def test_an_output_path_that_cannot_be_written_is_one_line_before_the_work(
    writer: str, kind: str, unwritable: dict[str, str]
) -> None:
    command, flag, argv = WRITERS[writer]
    path = unwritable[kind]
    done = dynevent(*argv(path))
    line = _one_line(done)
    assert done.stdout == "", done.stdout[-2_000:]  # refused before the command's work
    if command == "record" and kind == "a directory":
        assert line.endswith(": exists already (a bag is a new directory)"), line
        return
    assert line.startswith(f"dynevent {command}: {flag} {shown_path(path)}: cannot be written: "), line
    assert line.endswith(UNWRITABLE[kind]), line


def test_a_writable_output_path_is_tried_and_left_as_it_was(tmp_path: Path) -> None:
    kept = tmp_path / "kept.txt"
    kept.write_text("before", encoding="utf-8")
    files.check_writable(str(kept), "--report")
    files.check_writable(str(tmp_path / "new.xml"), "--junit")
    files.check_writable(str(tmp_path / "bag"), "--output", directory=True)
    files.check_writable(str(tmp_path), "--trace", directory=True)
    files.check_writable(os.devnull, "--trace")
    assert sorted(path.name for path in tmp_path.iterdir()) == ["kept.txt"]
    assert kept.read_text(encoding="utf-8") == "before"
    with pytest.raises(FileError, match=r"'.*kept.txt': cannot be written: Not a directory$"):
        files.check_writable(str(kept), "--trace", directory=True)
    with pytest.raises(FileError, match=r"cannot be written: a path cannot hold a NUL character$"):
        files.check_writable("a\0b", "--junit")


def test_a_shard_of_unicode_digits_is_refused_by_name() -> None:
    line = _one_line(dynevent("serve", "--shard", "\u00b2/\u00b2"))
    assert "--shard" in line and "expected K/N" in line, line


@pytest.mark.parametrize(
    ("config", "said"),
    [
        ({"categories": 5}, "categories: expected an object of category names (got 5)"),
        ({"rebegin": "x"}, "rebegin: expected a number of seconds, 0 and at most 86400 (got 'x')"),
        ({"rebegin": [1]}, "rebegin: expected a number of seconds, 0 and at most 86400 (got [1])"),
        ({"rebegin": 10**400}, "rebegin: expected a number of seconds, 0 and at most 86400"),
        (
            {"categories": {"clean": {"duration": "x"}}},
            "categories.clean.duration: expected a number of seconds",
        ),
        ({"categories": {"clean": 3}}, "categories.clean: expected an object"),
        (
            {"categories": {"clean": {"fail_on": 3}}},
            "categories.clean.fail_on: expected a list of place names",
        ),
        ({"fleet": 3}, "fleet: expected a string (got 3)"),
        ({"compatibility": "rmf"}, "compatibility: expected one of standard, rmf_ros2 (got 'rmf')"),
        ({"places": 3}, "places: expected a list of waypoint names"),
        ({"actions": [[]]}, "actions: expected a list of action names"),
        ([], "expected a JSON object (got [])"),
    ],
)
def test_every_wrong_value_of_serves_configuration_is_named(
    config: object, said: str, tmp_path: Path
) -> None:
    path = tmp_path / "serve.json"
    path.write_text(json.dumps(config), encoding="utf-8")
    line = _one_line(dynevent("serve", "--config", str(path)))
    assert str(path) in line and said in line, line


def test_the_reader_bounds_what_it_reads(tmp_path: Path) -> None:
    big = tmp_path / "big.json"
    big.write_bytes(b" " * 2_000)
    with pytest.raises(FileError, match="holds 2,000 bytes, more than 1,000"):
        files.read_bytes(str(big), "--config", limit=1_000)
    with pytest.raises(FileError, match="a path cannot hold a NUL character"):
        files.read_bytes("a\0b", "--config")
    files.write_text(str(tmp_path / "report.txt"), "a lone surrogate: \udc80", "--report")
    assert (tmp_path / "report.txt").read_text(encoding="utf-8") == "a lone surrogate: \\udc80"


def test_a_trace_line_past_the_bound_is_one_line_not_held_whole(tmp_path: Path) -> None:
    from dynevent.tools.check import MAX_TRACE_LINE

    huge = tmp_path / "huge.jsonl"
    with huge.open("wb") as stream:
        stream.write(b'{"type": "status", "x": "' + b"x" * (MAX_TRACE_LINE + 10))
    line = _one_line(dynevent("check", str(huge)))
    assert f"a line longer than {MAX_TRACE_LINE:,} bytes" in line, line
