#!/usr/bin/env python3
"""Measure the deployed adapter again, and compare it with the recordings CI holds dynevent to.

    python3 lab/rmf_ros2/measure.py --out DIR [--timeout 45] [--with-stubborn] [--skip-send]
                                    [--site full_control|easy]

In a shell with the lab's environment (Open-RMF's fleet adapter built from its sources over
dynevent's pinned wheels, dynevent with its bags extra installed in the same Python:
lab/rmf_ros2/README.md) and a ROS_DOMAIN_ID of the caller's, this:

1. starts the site (site/run_site.py, the robot added with full_control's parameters, or through
   EasyFullControl with ``--site easy``), and waits for its READY line;
2. records the robot (``dynevent record``) while ``dynevent probe`` runs every case (but
   ``stubborn.clamp_notice``, whose stubborn period takes the adapter down, D27, unless
   ``--with-stubborn``) with ``--known rmf_ros2``, its trace, report and JUnit kept;
3. records a ``dynevent send`` session (a NEXT; a NEXT cancelled while it runs; FINISHED);
4. stops the site, judges both recordings with ``dynevent check`` (rmf_ros2 compatibility), each
   finding labelled by the divergence it shows;
5. writes ``comparison.md``: per probe case the verdict then (tests/data/rmf_ros2/calibration) and
   now, and per divergence whether the recordings showed it then and the new ones show it now.

Every step is bounded; a step that fails is named in one line and the exit status is 1.  A
difference from the recordings is what the comparison reports, not a failure: the exit status is 0
once the comparison is written.  Nothing here builds anything.
"""

from __future__ import annotations

import argparse
import collections
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import IO

from dynevent.errors import DyneventError

HERE = Path(__file__).resolve().parent
DATA = HERE.parents[1] / "tests" / "data" / "rmf_ros2"
FLEET, ROBOT = "tinyRobot", "tinyRobot1"
PLACES = ("hall", "pantry", "lounge")
#: A probe case's line in the terminal report: its id and verdict (with a D-number).
CASE_LINE = re.compile(
    r"^([a-z_]+\.[a-z_0-9]+)\s{2,}((?:pass|fail|known|info|missing|non-strict)(?: \(\w+\))?)"
)
#: The bounds of the steps, in seconds.
UP, HEARD, STOP = 180.0, 60.0, 30.0


class Failed(Exception):
    """A step that did not do what it must: its one line."""


class Child:
    """A process whose output lines are read as they come (and kept in a log file)."""

    def __init__(self, argv: Sequence[str], log: Path) -> None:
        self.argv = list(argv)
        self.lines: collections.deque[str] = collections.deque(maxlen=10_000)
        self._log: IO[str] = log.open("w", encoding="utf-8")
        self.process = subprocess.Popen(
            self.argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True
        )
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line.rstrip("\n"))
            self._log.write(line)
            self._log.flush()

    def wait_line(self, prefix: str, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if any(line.startswith(prefix) for line in list(self.lines)):
                return
            if self.process.poll() is not None:
                raise Failed(f"{what}: the process ended (status {self.process.returncode}) first")
            time.sleep(0.1)
        raise Failed(f"{what}: not within {timeout:g} s")

    def stop(self) -> int:
        """SIGINT, then SIGTERM, then SIGKILL, each bounded; the exit status."""
        for signum, wait in ((signal.SIGINT, STOP), (signal.SIGTERM, 10.0), (signal.SIGKILL, 10.0)):
            if self.process.poll() is not None:
                break
            try:
                os.killpg(self.process.pid, signum)
            except ProcessLookupError:
                break
            try:
                self.process.wait(timeout=wait)
            except subprocess.TimeoutExpired:
                continue
        self._reader.join(timeout=5)
        self._log.close()
        return self.process.returncode if self.process.returncode is not None else -9


def dynevent(*args: str) -> list[str]:
    return [sys.executable, "-m", "dynevent", *args]


def run(argv: Sequence[str], log: Path, timeout: float) -> subprocess.CompletedProcess[str]:
    try:
        done = subprocess.run(argv, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        raise Failed(f"{' '.join(argv[2:5])}: not done within {timeout:g} s") from None
    log.write_text(f"{done.stdout}{done.stderr}EXIT {done.returncode}\n", encoding="utf-8")
    return done


def recording(out: Path, name: str) -> Child:
    """``dynevent record`` of the robot into ``out/name``, once it hears the robot's topics."""
    record = Child(
        dynevent("record", "-o", str(out / name), "--fleet", FLEET, "--robot", ROBOT), out / f"{name}.log"
    )
    record.wait_line(f"hearing /rmf/dynamic_event/status/{FLEET}/{ROBOT}", HEARD, f"the {name} recorder")
    return record


def probe(out: Path, timeout: float, with_stubborn: bool) -> subprocess.CompletedProcess[str]:
    from dynevent.conformance.probe.cases import CASES

    cases = [case.id for case in CASES if with_stubborn or case.id != "stubborn.clamp_notice"]
    argv = dynevent(
        "probe", "--fleet", FLEET, "--robot", ROBOT, "--place", *PLACES, "--timeout", f"{timeout:g}",
        "--deadline", f"{timeout * 4 * len(cases):g}", "--introspection", "--known", "rmf_ros2",
        "--trace", str(out / "probe.jsonl"), "--report", str(out / "probe.md"),
        "--junit", str(out / "probe.xml"), "--cases", *cases,
    )  # fmt: skip
    done = run(argv, out / "probe-known.txt", timeout * 5 * len(cases))
    if done.returncode == 2:
        said = (done.stderr.strip() or done.stdout.strip()).splitlines()[-1:] or ["(nothing said)"]
        raise Failed(f"the probe could not run: {said[0]}")
    return done


def send_session(out: Path) -> None:
    """A NEXT to pantry; a NEXT to lounge, cancelled while it runs; FINISHED."""

    def send(*args: str, timeout: float = 120.0) -> subprocess.CompletedProcess[str]:
        argv = dynevent("send", "--fleet", FLEET, "--robot", ROBOT, "--introspection", "--timeout", "60")
        argv += args
        try:
            done = subprocess.run(argv, capture_output=True, text=True, timeout=timeout, check=False)
        except subprocess.TimeoutExpired:
            raise Failed(f"send {' '.join(args)}: not done within {timeout:g} s") from None
        if done.returncode == 2:  # no server, no status, a bad request: the session cannot go on
            raise Failed(f"send {' '.join(args)}: {(done.stderr.strip() or done.stdout.strip())[-300:]}")
        return done

    said = [send("--place", "pantry")]
    lounge = dynevent("send", "--fleet", FLEET, "--robot", ROBOT, "--introspection", "--place", "lounge")
    walking = subprocess.Popen(lounge, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    time.sleep(5)
    said.append(send("--cancel"))
    try:
        walked, _ = walking.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        walking.kill()
        walked, _ = walking.communicate()
    said.append(send("--end"))
    (out / "send.txt").write_text(
        "\n".join([said[0].stdout, walked, said[1].stdout, said[2].stdout]), encoding="utf-8"
    )


# ------------------------------------------------------------------------------------- comparing


def verdicts(text: str) -> dict[str, str]:
    return {match[1]: match[2] for line in text.splitlines() if (match := CASE_LINE.match(line))}


def divergences_seen(bag: Path) -> collections.Counter[str]:
    """The labels of ``dynevent check``'s findings on a recording (rmf_ros2 compatibility)."""
    from dynevent.bags import check_bag
    from dynevent.conformance.judge.divergences import label

    report = check_bag(bag, compatibility="rmf_ros2")
    return collections.Counter(label(finding) for robot in report.robots for finding in robot.report.findings)


def comparison(out: Path, site: str = "full_control") -> str:
    then_verdicts = verdicts((DATA / "calibration" / "probe-known.txt").read_text("utf-8"))
    now_verdicts = verdicts((out / "probe-known.txt").read_text("utf-8"))
    lines = [
        "# The deployed adapter, measured again", "",
        f"Recordings then: {DATA} (calibration, probe, send: the full_control site); now: {out} "
        f"(the {site} site).", "",
        "## The probe's verdicts", "", "| case | then (calibration) | now |", "|---|---|---|",
    ]  # fmt: skip
    changed = 0
    for case in dict.fromkeys([*then_verdicts, *now_verdicts]):
        then, now = then_verdicts.get(case, "-"), now_verdicts.get(case, "not run")
        changed += then != now
        mark = "" if then == now else " **changed**"
        lines.append(f"| `{case}` | {then} | {now}{mark} |")
    then_seen: collections.Counter[str] = collections.Counter()
    for name in ("calibration", "probe", "send"):
        then_seen += divergences_seen(DATA / name)
    now_seen: collections.Counter[str] = collections.Counter()
    for name in ("probe-bag", "send-bag"):
        if (out / name).exists():
            now_seen += divergences_seen(out / name)
    lines += ["", "## What `dynevent check` finds in the recordings, by divergence", "",
              "| label | findings then | findings now |", "|---|---|---|"]  # fmt: skip
    for key in sorted(set(then_seen) | set(now_seen)):
        lines.append(f"| {key} | {then_seen.get(key, 0)} | {now_seen.get(key, 0)} |")
    lines += ["", f"{changed} case verdict(s) changed.", *replayed(out / "probe-bag")]
    return "\n".join(lines) + "\n"


def replayed(bag: Path) -> list[str]:
    """serve's rmf_ros2 mode driven through the new probe session (the clients' goals and the site's
    events, dynevent.conformance.judge.replay): each difference left, with the divergence it stands for
    ("?": none recorded yet), and the ids the site's children took."""
    from dynevent.bags import bag_records
    from dynevent.conformance.judge.divergences import label_difference
    from dynevent.conformance.judge.replay import compare_recording
    from dynevent.sim.config import ServeConfig, machine_config

    if not bag.exists():
        return []
    served = machine_config(ServeConfig(places=("dock", *PLACES, "lobby"), compatibility="rmf_ros2"))
    lines = ["", "## serve's rmf_ros2 mode, replayed through the new probe session", ""]
    for (fleet, robot), records in bag_records(bag).items():
        comparison = compare_recording(records, served, fleet=fleet, robot=robot, source=str(bag))
        lines.append(f"{fleet}/{robot}: {comparison.goals} goals replayed, {len(comparison.differences)} "
                     "difference(s)")  # fmt: skip
        lines += [f"- {', '.join(label_difference(item))}: {item}" for item in comparison.differences]
        lines += [f"- the site's ids: {item}" for item in comparison.counter]
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("--out", type=Path, required=True, help="where everything measured is written")
    parser.add_argument("--timeout", type=float, default=45.0, help="the probe's --timeout (default 45)")
    parser.add_argument("--with-stubborn", action="store_true", help="run stubborn.clamp_notice too (D27)")
    parser.add_argument("--skip-send", action="store_true", help="no send session")
    parser.add_argument("--site", choices=("full_control", "easy"), default="full_control",
                        help="how the site adds its robot (site/run_site.py --site)")  # fmt: skip
    args = parser.parse_args(argv)
    if "ROS_DOMAIN_ID" not in os.environ:
        print("measure: set ROS_DOMAIN_ID to a domain of your own first", file=sys.stderr)
        return 2
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    site: Child | None = None
    record: Child | None = None
    try:
        site = Child([sys.executable, str(HERE / "site" / "run_site.py"), "--logs", str(out / "site-logs"),
                      "--site", args.site], out / "site.log")  # fmt: skip
        site.wait_line("READY ", UP, "the site")
        say(f"site ready; probing (every wait up to {args.timeout:g} s)")
        record = recording(out, "probe-bag")
        done = probe(out, args.timeout, args.with_stubborn)
        last = done.stdout.strip().splitlines()[-1:] or [""]
        say(f"probe: exit {done.returncode}; {last[0]}")
        record.stop()
        record = None
        if not args.skip_send:
            site.wait_line("READY ", UP, "the site")
            record = recording(out, "send-bag")
            send_session(out)
            record.stop()
            record = None
            say("send session recorded")
    except Failed as exc:
        say(f"measure: {exc}")
        return 1
    finally:
        if record is not None:
            record.stop()
        if site is not None:
            site.stop()
    try:
        (out / "comparison.md").write_text(comparison(out, args.site), encoding="utf-8")
    except (OSError, DyneventError) as exc:
        say(f"measure: the comparison could not be written: {exc}")
        return 1
    say(f"comparison: {out / 'comparison.md'}")
    return 0


def say(text: str) -> None:
    print(text, flush=True)


if __name__ == "__main__":
    sys.exit(main())
