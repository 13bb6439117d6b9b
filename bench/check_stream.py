"""``dynevent check`` on a long trace: records per second and the process's peak memory.

Writes a clean trace of about ``--megabytes`` MB (child cycles from
bench/traces.py) to a temporary file, then runs ``python -m dynevent check``
on it in a child process and reports its wall time, records per second and
peak resident memory (``ru_maxrss``), beside the peak of a process that only
imports dynevent (the floor).  ``--write`` records the result as the
``check-stream`` section of bench/results.md.

    python bench/check_stream.py [--megabytes 100] [--write]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a script: make `bench` importable
    sys.path.insert(0, str(ROOT))

from bench import results  # noqa: E402
from bench.traces import cycle_lines  # noqa: E402

_CYCLE_BYTES = 1110  # one cycle's records, about


def _run(command: list[str]) -> tuple[float, int, str]:
    """Wall seconds, peak resident KiB and standard output of ``command``."""
    started = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    assert process.stdout is not None
    output = process.stdout.read().decode()
    _, status, usage = os.wait4(process.pid, 0)
    process.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - started
    if process.returncode not in (0,):
        raise SystemExit(f"{command}: exit {process.returncode}: {output[-500:]}")
    return wall, usage.ru_maxrss, output


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--megabytes", type=float, default=100.0, help="the trace's size (100)")
    parser.add_argument("--write", action="store_true", help="record the result in bench/results.md")
    args = parser.parse_args(argv)
    cycles = max(1, int(args.megabytes * 1e6 / _CYCLE_BYTES))
    with tempfile.TemporaryDirectory(prefix="dynevent-check-") as folder:
        trace = Path(folder) / "long.jsonl"
        with trace.open("w", encoding="utf-8") as out:
            out.writelines(cycle_lines(cycles))
        size = trace.stat().st_size
        _, floor_kib, _ = _run([sys.executable, "-c", "import dynevent.tools.check"])
        wall, peak_kib, output = _run([sys.executable, "-m", "dynevent", "check", str(trace)])
    records = int(output.rsplit(":", 1)[1].split()[0].replace(",", ""))
    lines = [
        "## `dynevent check` on a long trace (bench/check_stream.py)",
        "",
        f"A clean trace of {cycles:,} child cycles, {size / 1e6:.1f} MB, {records:,} records, checked by",
        "`python -m dynevent check` in a child process.",
        "",
        *results.machine_description(("dynevent",)),
        "",
        f"- {wall:.1f} s: **{records / wall:,.0f} records/s** (target: at least 40,000)",
        f"- peak resident memory: **{peak_kib / 1024:.1f} MB** (target: under 60 MB for 100 MB); "
        f"a process that only imports dynevent.tools.check: {floor_kib / 1024:.1f} MB",
    ]
    print("\n".join(lines))
    if args.write:
        results.write_section("check-stream", lines)
        print(f"wrote {results.RESULTS}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
