"""Completeness over DDS: every check of the machine the probe catches in process, switched off in the
real ``dynevent serve`` (tests/ros/broken_serve.py, the test kit's switch), is caught by ``dynevent
probe`` over DDS with the cases that caught it in process, or tests/support/completeness.py says why
DDS cannot show it.  What DDS caught is recorded there (``OVER_DDS``, docs/conformance.md's table
prints it): this test fails while the record and DDS differ.

One serve process per mode hosts a robot per check; the probes run two at a time, each as the
in-process measurement runs it but with a timeout of 2 s (a server that stops answering makes a case
wait it out; an answer over DDS on one machine comes within milliseconds)."""

from __future__ import annotations

import json
import shlex
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from ros_support import Child, child_env, finish

from dynevent.conformance.probe.cases import CASES
from dynevent.tools.live.serve import CALLBACK_FAULT
from support.completeness import CONFIG, DDS_CANNOT_SHOW, OPTIONS, OVER_DDS, Measured, dds_cases, measure

SCRIPT = Path(__file__).resolve().parent / "broken_serve.py"
#: The probe's --timeout, in seconds.
TIMEOUT = 2.0
#: How many probes run at once.
AT_ONCE = 2


#: The fleet each mode's serve process serves: one name each, so that their nodes' names differ (two
#: nodes of one name on a graph answer each other's parameter requests, ``dynevent task``'s).
FLEETS = {"standard": OPTIONS.fleet, "rmf_ros2": f"{OPTIONS.fleet}Compat"}


def _robot(rule: str) -> str:
    return "off_" + rule.replace(".", "_")


def _serve(tmp_path: Path, mode: str, measured: list[Measured]) -> Child:
    """``dynevent serve`` in ``mode`` as tests/support/completeness.py's CONFIG says, a robot per check
    of ``measured`` with that check switched off (no judge of the clients: its machine would step
    with the robots' switches in place)."""
    config = tmp_path / f"{mode}.json"
    categories = {
        name: {"duration": spec.duration, "report_every": spec.report_every}
        for name, spec in CONFIG.categories.items()
    }
    served = {"categories": categories, "rebegin": CONFIG.rebegin, "first_seq": CONFIG.first_seq}
    config.write_text(json.dumps({**served, "compatibility": mode}), encoding="utf-8")
    pairs = ",".join(f"{_robot(item.rule)}={item.rule}" for item in measured)
    return Child([str(SCRIPT), "switched_off", pairs, "--fleet", FLEETS[mode], "--config", str(config),
                  "--no-judge"])  # fmt: skip


def _probe(item: Measured, mode: str) -> subprocess.CompletedProcess[str]:
    """The probe over DDS, with the options of the in-process measurement, of ``item``'s robot, its task
    interrupted and resumed by ``dynevent task`` (the cases that interrupt it run)."""
    assert OPTIONS.place is not None
    known = ["--known", "rmf_ros2"] if mode == "rmf_ros2" else []
    robot = _robot(item.rule)
    task = f"{shlex.quote(sys.executable)} -m dynevent task --fleet {FLEETS[mode]} --robot {robot}"
    tasks = ["--interrupt-command", f"{task} interrupt", "--resume-command", f"{task} resume"]
    command = [sys.executable, "-m", "dynevent", "probe", "--fleet", FLEETS[mode],
               "--robot", robot, "--place", OPTIONS.place, *OPTIONS.more_places,
               "--timeout", str(TIMEOUT), *known, *tasks, "--cases", *dds_cases(item)]  # fmt: skip
    process = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env()
    )
    return finish(process, 120)


def _caught(rule: str, done: subprocess.CompletedProcess[str]) -> tuple[str, ...]:
    """What the probe's run caught, as the in-process measurement reads it: nothing unless it exits 1;
    then the cases that failed, or ``"the judge"`` when none did (and the judge's section names the
    rule)."""
    if done.returncode != 1:
        assert done.returncode in (0, 3), done.stdout + done.stderr  # passed, or cases not run
        return ()
    ids = {case.id for case in CASES}
    failed: list[str] = []
    for line in done.stdout.splitlines():
        words = line.split()
        if len(words) > 1 and words[0] in ids and words[1] == "fail" and words[0] not in failed:
            failed.append(words[0])
    if failed:
        return tuple(failed)
    _, _, judged = done.stdout.partition("the judge, over every record of the exchange: ")
    assert f": fail: {rule} " in judged, done.stdout + done.stderr
    return ("the judge",)


def test_every_check_the_probe_catches_in_process_is_caught_over_dds(tmp_path: Path) -> None:
    caught_in_process = [item for item in measure() if item.probe["in process"][1]]
    by_mode: dict[str, list[Measured]] = {}
    for item in caught_in_process:
        by_mode.setdefault(item.probe["in process"][0], []).append(item)
    began = time.monotonic()
    servers = {mode: _serve(tmp_path, mode, items) for mode, items in by_mode.items()}

    def probe(item: Measured) -> tuple[tuple[str, ...], str]:
        started = time.monotonic()
        done = _probe(item, item.probe["in process"][0])
        caught = _caught(item.rule, done)
        print(f"{item.rule}: {caught} in {time.monotonic() - started:.1f} s")
        return caught, done.stdout + done.stderr

    try:
        for serve in servers.values():
            serve.wait_line("serving ")
        with ThreadPoolExecutor(AT_ONCE) as pool:
            ran = dict(zip([item.rule for item in caught_in_process], pool.map(probe, caught_in_process),
                           strict=True))  # fmt: skip
    finally:
        codes = {mode: serve.stop() for mode, serve in servers.items()}
    seen = {rule: caught for rule, (caught, _) in ran.items()}
    outputs = {rule: output for rule, (_, output) in ran.items()}
    print(f"{len(seen)} checks probed over DDS in {time.monotonic() - began:.1f} s")
    assert codes == dict.fromkeys(servers, 0), {mode: serve.output for mode, serve in servers.items()}
    faults = [
        line for serve in servers.values() for line in serve.output.splitlines() if CALLBACK_FAULT in line
    ]
    assert faults == [], faults  # a check switched off may not make serve's own code raise
    record = "".join(f'    "{rule}": {cases!r},\n'.replace("'", '"') for rule, cases in seen.items())
    served = "".join(serve.output for serve in servers.values()).splitlines()
    differing = {  # what the probe said, and what serve said of the robot
        rule: outputs[rule] + "\n".join(line for line in served if f"/{_robot(rule)} " in line)
        for rule, cases in seen.items()
        if cases != OVER_DDS.get(rule)
    }
    assert seen == dict(OVER_DDS), (
        f"OVER_DDS differs from what DDS shows; what it shows:\n{record}\n{differing}"
    )
    unexplained = [rule for rule, cases in seen.items() if not cases and rule not in DDS_CANNOT_SHOW]
    assert unexplained == [], {rule: outputs[rule] for rule in unexplained}
    stale = [rule for rule, cases in seen.items() if cases and rule in DDS_CANNOT_SHOW]
    assert stale == [], "caught over DDS, yet DDS_CANNOT_SHOW says DDS cannot show it"
