"""The progress line of long commands: on a terminal only, rate-limited, erased before the report."""

from __future__ import annotations

import io
import os
import pty
import subprocess
import sys
from pathlib import Path

from dynevent.tools._progress import Progress

ROOT = Path(__file__).resolve().parents[2]


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_terminal_sees_the_line_and_its_erasure() -> None:
    screen = Terminal()
    progress = Progress("dynevent check: t.jsonl", 200, stream=screen, interval=0.0)
    progress.update(50, "(line 7)")
    progress.update(200)
    progress.close()
    assert screen.getvalue() == (
        "\rdynevent check: t.jsonl: 25% (line 7)\x1b[K\rdynevent check: t.jsonl: 100%\x1b[K\r\x1b[K"
    )


def test_without_a_total_it_counts() -> None:
    screen = Terminal()
    progress = Progress("work", stream=screen, interval=0.0)
    progress.update(12345)
    assert "work: 12,345" in screen.getvalue()


def test_a_pipe_sees_nothing_and_quick_work_shows_nothing() -> None:
    piped = io.StringIO()
    progress = Progress("x", 10, stream=piped, interval=0.0)
    progress.update(5)
    progress.close()
    assert piped.getvalue() == ""
    screen = Terminal()
    quick = Progress("x", 10, stream=screen)  # the first line waits one interval
    quick.update(5)
    quick.close()
    assert screen.getvalue() == ""


def _through_a_terminal(argv: list[str]) -> tuple[subprocess.CompletedProcess[bytes], bytes]:
    """Run ``python -m dynevent ARGV`` with standard error on a real pseudo-terminal."""
    leader, follower = pty.openpty()
    try:
        done = subprocess.run(
            [sys.executable, "-m", "dynevent", *argv],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=follower,
            cwd=ROOT,
            timeout=120,
            check=False,
        )
        os.close(follower)
        follower = -1
        seen = b""
        while True:
            try:
                chunk = os.read(leader, 65536)
            except OSError:  # the terminal's other end is closed: everything is read
                break
            if not chunk:
                break
            seen += chunk
    finally:
        if follower != -1:
            os.close(follower)
        os.close(leader)
    return done, seen


def test_check_on_a_terminal_shows_progress_and_erases_it_before_the_report(tmp_path: Path) -> None:
    """A trace long enough to take a second: a terminal sees the progress, a pipe the same report alone."""
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    from bench.traces import cycle_lines

    trace = tmp_path / "long.jsonl"
    trace.write_text("".join(cycle_lines(4000)), encoding="utf-8")
    done, seen = _through_a_terminal(["check", str(trace)])
    piped = subprocess.run(
        [sys.executable, "-m", "dynevent", "check", str(trace)],
        capture_output=True,
        cwd=ROOT,
        timeout=120,
        check=False,
    )
    assert done.returncode == piped.returncode == 0
    assert done.stdout == piped.stdout and b": 28002 records, no violations" in piped.stdout
    assert piped.stderr == b""
    assert f"dynevent check: {trace}: ".encode() in seen and b"% (line " in seen
    assert seen.endswith(b"\r\x1b[K")
