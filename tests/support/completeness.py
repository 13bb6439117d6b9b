"""Completeness, measured: each check of the machine switched off (dynevent.testing.switched_off),
run against the vectors and the probe's in-process links; what catches it; and what the probe over
DDS caught, as tests/ros/test_ros_completeness.py measures it (:data:`OVER_DDS`).  Shared by
tests/conformance/test_completeness.py, the ROS test and the table docs/conformance.md prints.  Not
a test module."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import attrs

from dynevent.conformance.probe.cases import CASES, KNOWN, KNOWN_MISSING, CaseFinding, Verdict
from dynevent.conformance.probe.in_process import probe_in_process
from dynevent.conformance.probe.runner import Options
from dynevent.conformance.vectors import InProcessImplementation, Vector, load_vectors, run_vectors
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.holder import RobotServer
from dynevent.sim.config import CategorySpec, ServeConfig, machine_config
from dynevent.testing import switched_off as kit

#: serve as the probe's own tests run it: brief children that log often, the first run at the seq wrap.
CONFIG = ServeConfig(
    categories={"go_to_place": CategorySpec(duration=0.5, report_every=0.1)}, rebegin=0.3, first_seq=2**32 - 1
)
OPTIONS = Options(fleet="tinyRobot", robot="tinyRobot1", place="pantry", more_places=("lounge",), timeout=3)
#: The probe's links measured here: the machine stepped in process (``--loopback``), and the same
#: machine behind the driver protocol (``--impl``), each in both compatibility modes.
LINKS = ("in process", "driver")
MODES = ("standard", "rmf_ros2")


#: How many of the cases that caught a check in process the probe over DDS runs: the first (a case
#: against a server that stops answering waits out the timeout, and the whole test keeps to a couple
#: of minutes).
DDS_CASES = 1

#: The cases the probe over DDS runs besides a check's own, per rule, and why.
DDS_ADDED: Mapping[str, tuple[tuple[str, ...], str]] = {
    "R2.3": (
        ("next.status_after_child",),
        "dynevent's ROS binding publishes the robot's status when it starts, whatever the machine says "
        "(for a late joiner, R1.4): status.latched passes, and the statuses the machine no longer "
        "publishes show from a child's end on",
    ),
    "R4.3": (
        ("finished.ends_the_run",),
        "finished.finished_after runs only once the probe has seen a run end",
    ),
}

#: What the probe over DDS caught, per check the probe catches in process: the cases that failed
#: (``"the judge"`` when only the judge over every record found it), run in the mode and with the
#: cases of :func:`dds_cases` against ``dynevent serve`` with that check switched off.  Recorded
#: from tests/ros/test_ros_completeness.py, which fails while it differs from what DDS shows.
OVER_DDS: Mapping[str, tuple[str, ...]] = {
    "R4.2": ("request.seq_stale",),
    "R4.3": ("finished.finished_after",),
    "R4.4": ("request.event_type_0",),
    "R4.5": ("request.event_type_unknown",),
    "R4.6": ("next.busy",),
    "R4.7": ("request.category_unknown",),
    "R4.9": ("next.runs_a_child",),
    "R4.10": ("request.description_invalid",),
    "R4.11": ("request.stubborn_nan",),
    "R4.12": ("next.id_stale",),
    "R4.13": ("request.cancel_idle",),
    "R4.14": ("cancel.wrong_id",),
    "R2.3": ("next.status_after_child",),
    "R3.1": ("the judge",),
    "R3.3": ("status.waiting",),
    "R4.16": (),
    "R5.2": (),
    "R6.3": ("interrupt.deferred_start",),
    "R6.4": ("next.runs_a_child",),
    "R8.1": ("next.runs_a_child",),
    "R8.2": ("next.runs_a_child",),
    "R8.3": ("next.busy",),
    "R8.4": ("next.status_after_child",),
    "R9.1": ("request.cancel_idle",),
    "R9.2": ("cancel.wrong_id",),
    "R9.3": ("cancel.running_child",),
    "R9.4": ("interrupt.cancel_deferred",),
    "R10.1": (),
    "R10.2": ("action.cancel_waiting",),
    "R10.3": ("action.cancel_running",),
    "R10.4": ("interrupt.action_cancel_deferred",),
    "R10.5": (),
    "R11.1": ("finished.ends_the_run",),
    "R12.2": ("stubborn.clamp_notice",),
    "R14.5": ("interrupt.deferred_start",),
    "R16.1": (),
    "R17.2": ("request.event_type_0",),
    "R17.4": ("next.status_after_child",),
}

_BINDING = "dynevent's ROS binding {does}: with the machine's {what} dropped, a client sees it as before"

#: Why the probe over DDS cannot show a check it catches in process, per rule.
DDS_CANNOT_SHOW: Mapping[str, str] = {
    "R16.1": _BINDING.format(
        does="answers a description query the machine gives no answer to with the defaults, which are "
        "R16.1's answer (a service callback must return one, and an exception would end the thread of "
        "every robot of its lane: found when this check ended a lane)",
        what="answer",
    ),
    "R4.16": _BINDING.format(
        does="accepts every goal request the machine does not refuse (rclpy's goal callback answers "
        "ACCEPT or REJECT, and an acceptance carries nothing more)",
        what="acceptance",
    ),
    "R5.2": "dynevent's ROS binding submits an accepted goal, request and start in one step under its "
    "lock (R5.3): no goal is asked for between a goal's acceptance and its start, and a race it loses "
    "there is R5.3's",
    "R10.1": "dynevent's ROS binding submits an accepted goal, request and start in one step under its "
    "lock (R5.3): no goal waits to start for an action-level cancel to find",
    "R10.5": _BINDING.format(
        does="refuses every action-level cancel the machine does not accept (rclpy's cancel callback "
        "answers ACCEPT or REJECT)",
        what="refusal",
    ),
}


@attrs.frozen
class Measured:
    """What caught one switched-off check: the first vector that fails (those that cite its rule run
    first); whether the probe's exchange reached it (a step where the server did other than the
    machine); per probe link the cases that fail in the first mode where any does (``"the judge"``
    when only the judge over every record found it), with that mode; empty: not caught."""

    switch: kit.Switch
    vector: str | None
    reached: bool
    probe: dict[str, tuple[str, tuple[str, ...]]]

    @property
    def rule(self) -> str:
        return self.switch.rule


def _unasked(path: str, text: str, flag: str) -> None:
    """The report writer of a run that asks for no report: it is never called."""
    raise AssertionError(f"{flag} {path}: written, though the run asked for no report")


def _probe(rule: str, link: str, mode: str) -> tuple[bool, tuple[str, ...]]:
    """Whether the probe's exchange over ``link`` in ``mode`` reached the check (a step where the
    switched-off server did other than the machine), and the cases that caught it."""
    config = attrs.evolve(CONFIG, compatibility=mode)
    options = OPTIONS
    if mode == "rmf_ros2":  # what rmf_ros2 mode fails on by design is known: the rest is caught
        options = attrs.evolve(options, known=KNOWN["rmf_ros2"], known_missing=KNOWN_MISSING["rmf_ros2"])
    reached = [link == "driver"]
    if link == "driver":
        implementation = kit.switched_off_implementation(InProcessImplementation(), rule)
        code, findings = probe_in_process(
            options, list(CASES), lambda _: None, config, write=_unasked, implementation=implementation
        )
    else:
        first = config.first_state(options.robot)
        server = RobotServer(options.fleet, options.robot, machine_config(config), first)
        switched = kit.switched_off_stepper(server.step, rule)

        def stepper(event: ins.Input) -> tuple[outs.Output, ...]:
            before = server.state
            outputs = switched(event)
            if not reached[0]:
                transition = machine.step(before, event, server.config)  # the machine, as it is
                reached[0] = (transition.state, transition.outputs) != (server.state, outputs)
            return outputs

        code, findings = probe_in_process(
            options, list(CASES), lambda _: None, config, write=_unasked, stepper=stepper
        )
    if code != 1:  # passed, or only cases not run (exit 3): no case named what broke
        return reached[0], ()
    failed = tuple(f.case.id for f in findings if f.verdict is Verdict.FAIL and not f.known)
    return reached[0], failed or ("the judge",)


def probe_published_at_start(rule: str, link: str) -> tuple[int, list[CaseFinding]]:
    """Every case, over ``link``, against a server that publishes its first status (as dynevent's ROS
    binding publishes the robot's status when it starts, for a late joiner) and has ``rule`` switched
    off from then on: the exit status and the findings."""
    first: list[ins.Input] = []
    if link == "driver":
        inner = InProcessImplementation()
        switched_driver = kit.switched_off_implementation(inner, rule)

        class Published:  # the first input (the run's begin) stepped by the machine as it is
            name = switched_driver.name

            def reset(self, *args: Any) -> None:
                switched_driver.reset(*args)

            def apply(self, event: Any) -> tuple[list[Any], Any]:
                if not first:
                    first.append(event)
                    result: tuple[list[Any], Any] = inner.apply(event)
                    return result
                return switched_driver.apply(event)  # type: ignore[no-any-return]

            def close(self) -> None:
                switched_driver.close()

        return probe_in_process(
            OPTIONS, list(CASES), lambda _: None, CONFIG, write=_unasked, implementation=Published()
        )
    first_state = CONFIG.first_state(OPTIONS.robot)
    server = RobotServer(OPTIONS.fleet, OPTIONS.robot, machine_config(CONFIG), first_state)
    switched = kit.switched_off_stepper(server.step, rule)

    def stepper(event: ins.Input) -> tuple[outs.Output, ...]:
        if not first:
            first.append(event)
            return tuple(server.step(event))
        return switched(event)

    return probe_in_process(OPTIONS, list(CASES), lambda _: None, CONFIG, write=_unasked, stepper=stepper)


def _first_vector(rule: str, vectors: list[Vector]) -> str | None:
    ordered = sorted(vectors, key=lambda vector: rule not in vector.rules)
    implementation = kit.switched_off_implementation(InProcessImplementation(), rule)
    for outcome in run_vectors(ordered, implementation, max_failures=1):
        if outcome.failure is not None:
            return outcome.vector.name
    return None


def _caught_by_probe(rule: str) -> tuple[bool, dict[str, tuple[str, tuple[str, ...]]]]:
    """Whether the probe's exchange reached ``rule`` switched off, in either mode; and per link, the
    first mode in which the probe caught it and the cases.  The driver link runs once, in the mode the
    in-process link caught it in (else the standard mode), and only where the in-process exchange
    reached the check (else the driver link's exchange, the same, cannot catch it)."""
    reached_any = False
    caught: dict[str, tuple[str, tuple[str, ...]]] = {link: ("", ()) for link in LINKS}
    for mode in MODES:
        reached, cases = _probe(rule, "in process", mode)
        reached_any = reached_any or reached
        if cases:
            caught["in process"] = (mode, cases)
            break
    if reached_any:
        mode = caught["in process"][0] or "standard"
        cases = _probe(rule, "driver", mode)[1]
        caught["driver"] = (mode, cases) if cases else ("", ())
    return reached_any, caught


@functools.cache
def measure() -> tuple[Measured, ...]:
    """Every check of the machine, switched off, against the vectors and each probe link."""
    vectors = load_vectors()
    return tuple(
        Measured(switch, _first_vector(switch.rule, vectors), *_caught_by_probe(switch.rule))
        for switch in kit.switches()
    )


def dds_cases(measured: Measured) -> tuple[str, ...]:
    """The cases the probe over DDS runs against ``measured``'s check switched off, in the probe's
    order: the first :data:`DDS_CASES` that caught it in process (every case where only the judge
    did), and those :data:`DDS_ADDED` gives it."""
    caught = measured.probe["in process"][1]
    chosen = set(caught[:DDS_CASES]) | set(DDS_ADDED.get(measured.rule, ((), ""))[0])
    return tuple(case.id for case in CASES if caught == ("the judge",) or case.id in chosen)


def _cases(caught: tuple[str, tuple[str, ...]]) -> str:
    mode, cases = caught
    if not cases:
        return "no"
    shown = ", ".join(f"`{case}`" if "." in case else case for case in cases[:2])
    more = f" (+{len(cases) - 2})" if len(cases) > 2 else ""
    return shown + more + (f" ({mode})" if mode != "standard" else "")


def _over_dds(measured: Measured) -> str:
    if not measured.probe["in process"][1]:
        return "not run"  # only what the probe catches in process is probed over DDS
    return _cases((measured.probe["in process"][0], OVER_DDS.get(measured.rule, ())))


def table(reasons: Mapping[str, str]) -> str:
    """docs/conformance.md's table of completeness, a row a check: ``reasons`` why no live exchange
    shows a check, and :data:`DDS_CANNOT_SHOW` why DDS does not."""
    lines = [
        "| rule | switched off | vectors: first to catch it | probe in process | probe over the driver | "
        "probe over DDS | why no live exchange, or DDS, shows it |",
        "|---|---|---|---|---|---|---|",
    ]
    for measured in measure():
        why = reasons.get(measured.rule, "")
        if measured.rule in DDS_CANNOT_SHOW:
            why = f"over DDS: {DDS_CANNOT_SHOW[measured.rule]}"
        cells = [
            measured.rule,
            measured.switch.how,
            f"`{measured.vector}`" if measured.vector else "no",
            _cases(measured.probe["in process"]),
            _cases(measured.probe["driver"]),
            _over_dds(measured),
            why,
        ]
        lines.append("| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |")
    return "\n".join(lines) + "\n"
