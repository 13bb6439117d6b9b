"""The documentation shows what the code does: every session and example in it runs, here.

- Every ```` ```console ```` block of README.md and docs/*.md is a session: each
  ``$ command`` line is run (``dynevent`` as this interpreter's ``-m dynevent``,
  ``python`` inside it as this interpreter; ``echo $?`` echoes the last exit
  status; ``< FILE`` feeds a file) from the project's root, and what it prints
  must be the lines that follow, exactly.  Sessions of the ROS commands
  (``dynevent serve``, ``send``) need a ROS graph and are left to tests/ros.
- Every ```` ```python ```` block of the pages in :data:`PYTHON_PAGES` runs, top
  level statement by top level statement; a ``print(...)`` with a comment (on
  its line, or alone on the next) must print exactly that comment.

``DYNEVENT_UPDATE_DOCS=1 python -m pytest tests/project/test_docs_examples.py``
rewrites the console sessions from what the commands print now.
"""

from __future__ import annotations

import ast
import io
import os
import re
import shlex
import subprocess
import sys
import tokenize
from pathlib import Path

import pytest

from support.doc_sessions import CONSOLE, sessions

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
PAGES = [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]
PYTHON_PAGES = [
    ROOT / "README.md",
    *(DOCS / name for name in ("testing-your-implementation.md", "client.md", "fleet.md", "descriptions.md")),
]
ROS_COMMANDS = ("dynevent serve", "dynevent send")


def _runnable(pairs: list[tuple[str, str]]) -> bool:
    return not any(command.startswith(ROS_COMMANDS) for command, _ in pairs)


def _word(word: str) -> str:
    """A word of a documented command line, with ``python`` as this interpreter."""
    return re.sub(r"^python(?= |$)", shlex.quote(sys.executable), word)


def run(command: str, previous: int) -> tuple[str, int]:
    """The console output of one documented command, and its exit status."""
    if command == "echo $?":
        return f"{previous}\n", previous
    stdin = None
    if " < " in command:
        command, path = command.split(" < ")
        stdin = (ROOT / path.strip()).read_text(encoding="utf-8")
    words = [_word(word) for word in shlex.split(command)]
    assert words[0] == "dynevent", command
    done = subprocess.run(
        [sys.executable, "-m", "dynevent", *words[1:]],
        input=stdin,
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
        check=False,
    )
    assert "Traceback" not in done.stderr, done.stderr
    return _TOOK.sub(r"\g<1>0.0 s", done.stdout + done.stderr), done.returncode


#: The last line of a run of the vectors or the probe: the seconds it took are the machine's of the
#: moment, so a session shows them as 0.0 (the line itself, and where it stands, are checked).
_TOOK = re.compile(r"^(the run took )\d+\.\d s", re.MULTILINE)


def _render(text: str) -> str:
    def block(match: re.Match[str]) -> str:
        pairs = sessions(match.group(0))[0]
        if not _runnable(pairs):
            return match.group(0)
        previous = 0
        parts = []
        for command, _ in pairs:
            output, previous = run(command, previous)
            parts.append(f"$ {command}\n{output}")
        return "```console\n" + "".join(parts) + "```"

    return CONSOLE.sub(block, text)


SESSION_PAGES = [page for page in PAGES if any(map(_runnable, sessions(page.read_text(encoding="utf-8"))))]


@pytest.mark.parametrize("page", SESSION_PAGES, ids=[page.name for page in SESSION_PAGES])
def test_console_sessions_show_what_the_commands_print(page: Path) -> None:
    text = page.read_text(encoding="utf-8")
    if os.environ.get("DYNEVENT_UPDATE_DOCS"):
        page.write_text(_render(text), encoding="utf-8")
        text = page.read_text(encoding="utf-8")
    for pairs in filter(_runnable, sessions(text)):
        previous = 0
        for command, expected in pairs:
            output, previous = run(command, previous)
            assert output == expected, f"{page.name} is stale for: $ {command}\n--- it prints:\n{output}"


def test_the_pages_named_by_the_docs_promise_have_sessions() -> None:
    names = {page.name for page in SESSION_PAGES}
    assert {"cli.md", "conformance.md", "testing-your-implementation.md"} <= names


# --------------------------------------------------------------------------- Python examples


def _comments(source: str) -> dict[int, str]:
    """Each line's comment text (without ``#``), by line number."""
    found = {}
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.COMMENT:
            found[token.start[0]] = token.string[1:].strip()
    return found


def _claims(tree: ast.Module, lines: list[str], comments: dict[int, str]) -> dict[tuple[int, int], str]:
    """What each ``print(...)`` call's comment says it prints, by the call's (first, last) line: the
    comment on its last line, or a comment line of its own right after it."""
    found = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "print":
            end = node.end_lineno or node.lineno
            if end in comments and not lines[end - 1].lstrip().startswith("#"):
                found[(node.lineno, end)] = comments[end]
            elif end < len(lines) and lines[end].lstrip().startswith("#"):
                found[(node.lineno, end)] = comments[end + 1]
    return found


EXAMPLES = [
    (page.name, index, block)
    for page in PYTHON_PAGES
    for index, block in enumerate(re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), re.S))
]


@pytest.mark.parametrize(("page", "index", "block"), EXAMPLES, ids=[f"{p}#{i + 1}" for p, i, _ in EXAMPLES])
def test_python_example_prints_what_its_comments_say(page: str, index: int, block: str) -> None:
    name = f"docs/{page} example {index + 1}"
    tree = ast.parse(block, name)
    claims = _claims(tree, block.splitlines(), _comments(block))
    printed: dict[int, list[str]] = {}

    def recording_print(*values: object, sep: str = " ", end: str = "\n", **_: object) -> None:
        line = sys._getframe(1).f_lineno
        printed.setdefault(line, []).append(sep.join(map(str, values)))

    exec(compile(tree, name, "exec"), {"__name__": f"docs_example_{index}", "print": recording_print})
    for (first, last), expected in claims.items():
        said = [text for line in range(first, last + 1) for text in printed.get(line, [])]
        assert said, f"{name}, line {first}: the print never ran"
        assert all(text == expected for text in said), (
            f"{name}, line {first}: printed {said}, not {expected!r}"
        )
    if "print(" in block:
        assert claims, f"{name} prints but claims nothing about what"
