"""Servers with one check of the machine switched off: what the vectors and the probe must catch.

Every check of :mod:`dynevent.server.machine` is enrolled from the machine itself, so that a check
added there is measured here without a word written:

- each entry of :data:`~dynevent.server.machine.REQUEST_CHECKS` (R4.1 to R4.14): switched off, it
  is left out of the table its walks are compiled from (:func:`accept`'s, the start's re-check of
  R6.1 and the checks rmf_ros2 mode defers), so that a goal it would refuse passes on to the next;
- each rule its steps carry out (every rule the machine's source names as a value: the rule of an
  output, of an ignored input, of a phase change in ``TRANSITIONS``): switched off, the outputs
  the machine gives under that rule are dropped, or, where the rule decides something rather than
  says it (:data:`DECISIONS`), that decision is not taken.

A switch is a test hook of this kit, never of the shipped machine: the machine's module attributes
are replaced while a switched-off server steps (:func:`switched_off`), and put back before anything
else, a judge included, reads them.  The machine's code carries no switch and pays nothing for one.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import inspect
import re
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

import attrs

from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import RequestCheck, ServerConfig, State, Transition
from dynevent.testing.broken import patched

__all__ = [
    "DECISIONS",
    "Switch",
    "check_rules",
    "step_rules",
    "switch",
    "switched_off",
    "switched_off_implementation",
    "switched_off_stepper",
    "switches",
]

_RULE = re.compile(r"R\d+\.\d+")


def _rule_key(rule: str) -> tuple[int, ...]:
    return tuple(int(part) for part in rule[1:].split("."))


def check_rules() -> tuple[str, ...]:
    """The rules of the machine's request checks, in the order :func:`~dynevent.server.machine.accept`
    runs them."""
    return tuple(check.rule for check in machine.REQUEST_CHECKS)


@functools.cache
def step_rules() -> tuple[str, ...]:
    """Every other rule the machine's source names as a value (``rule="R8.2"``, ``_ignored("R18.4",
    ...)``, an edge of ``TRANSITIONS``), in the order of docs/spec.md: the rules its steps carry out."""
    tree = ast.parse(inspect.getsource(machine))
    named = {
        node.value
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and _RULE.fullmatch(node.value)
    }
    return tuple(sorted(named - set(check_rules()), key=_rule_key))


#: An output as the switched-off server gives it (None: not at all), from the input the step was given
#: and the machine's output.
Rewrite = Callable[[ins.Input, outs.Output], "outs.Output | None"]


@attrs.frozen
class Switch:
    """One check switched off: ``rule``, ``kind`` (``"request check"`` or ``"step"``), what the
    server does instead (``how``), the machine's attributes replaced while it steps (``patches``)
    and how its outputs are rewritten (``rewrite``)."""

    rule: str
    kind: str
    how: str
    patches: Mapping[str, Any] = attrs.field(factory=dict)
    rewrite: Rewrite | None = None


# ------------------------------------------------------------------ request checks


class _AnyType(dict):  # type: ignore[type-arg]
    """The machine's acceptances with one for every event type: a goal of a type R4.4 or R4.5 would
    refuse is accepted as the others are (and aborted at its start, as rmf_ros2 mode aborts it)."""

    def __missing__(self, event_type: int) -> outs.Accepted:
        return outs.Accepted(event_type=event_type, rule="R4.16")


def _unknown_category_passes(check: RequestCheck) -> RequestCheck:
    """R4.10 for a server that never checked the category (R4.7): a category it lacks has no schema."""
    validate = check.check

    def described(state: State, goal: Any, config: ServerConfig, found: list[Any]) -> outs.Rejected | None:
        return validate(state, goal, config, found) if goal.category in config.categories else None

    return attrs.evolve(check, check=described)


def _without_check(rule: str) -> Switch:
    kept = tuple(check for check in machine.REQUEST_CHECKS if check.rule != rule)
    if rule == "R4.7":
        kept = tuple(_unknown_category_passes(c) if c.rule == "R4.10" else c for c in kept)
    patches: dict[str, Any] = {"REQUEST_CHECKS": kept, "_ACCEPTANCES": _AnyType(machine._ACCEPTANCES)}
    saved = machine.REQUEST_CHECKS
    machine.REQUEST_CHECKS = kept  # _walk and _deferred read the table: compiled from the copy
    try:
        patches["_STANDARD_WALKS"] = tuple(
            machine._compiled_walk(machine._walk(True, kind), f"{rule} off, standard, type {kind}")
            for kind in range(5)
        )
        patches["_RMF_ROS2_WALKS"] = tuple(
            machine._compiled_walk(machine._walk(False, kind), f"{rule} off, rmf_ros2, type {kind}")
            for kind in range(5)
        )
        patches["_DEFERRED"] = tuple(machine._deferred(kind) for kind in range(5))
    finally:
        machine.REQUEST_CHECKS = saved
    patches["_DESCRIPTION_CHECKS"] = tuple(
        check.check for check in kept if check.rule in ("R4.7", "R4.8", "R4.9", "R4.10")
    )
    what = next(check for check in machine.REQUEST_CHECKS if check.rule == rule)
    return Switch(rule, "request check", _check_how(what), patches)


def _check_how(check: RequestCheck) -> str:
    return f"no goal is refused {check.reason.value} (the check is left out of the table)"


# ------------------------------------------------------------------ step rules


def _dropped(rule: str) -> Rewrite:
    def rewrite(event: ins.Input, output: outs.Output) -> outs.Output | None:
        return None if output.rule == rule else output

    return rewrite


def _handler(kind: type, change: Callable[[State, Any, ServerConfig, Transition], Transition]) -> Any:
    """The machine's dispatch with the handler of ``kind`` changed: ``change(state, event, config,
    transition)`` gives the step's transition from the machine's own."""
    by_class = dict(machine._BY_CLASS)
    original = by_class[kind]

    def handler(state: State, event: Any, config: ServerConfig) -> Transition:
        return change(state, event, config, original(state, event, config))

    by_class[kind] = handler
    return by_class


def _child_end_unpublished(event: ins.Input, output: outs.Output) -> outs.Output | None:
    return None if isinstance(event, ins.ChildFinished) and isinstance(output, outs.PublishStatus) else output


def _no_child_in_result(event: ins.Input, output: outs.Output) -> outs.Output | None:
    if isinstance(output, outs.AnswerGoal) and output.rule in (
        machine.CHILD_END_RULE,
        machine.WAITING_CANCEL_RULE,
    ):
        return attrs.evolve(output, result=attrs.evolve(output.result, status="", id=0))
    return output


def _unwarned_clamp(event: ins.Input, output: outs.Output) -> outs.Output | None:
    if output.rule == "R12.2":
        return None
    if (
        isinstance(output, outs.PublishFeedback)
        and output.feedback.logs
        and isinstance(event, (ins.GoalStarted, ins.GoalSubmitted))  # a binding's start comes submitted
    ):
        return attrs.evolve(output, feedback=attrs.evolve(output.feedback, logs=()))
    return output


def _signal_forgotten(state: State, event: Any, config: ServerConfig, transition: Transition) -> Transition:
    if not state.task_signal:
        return transition
    return machine._on_child_finished(attrs.evolve(state, task_signal=""), event, config)


def _still_active(state: State, event: Any, config: ServerConfig, transition: Transition) -> Transition:
    after = attrs.evolve(transition.state, active=state.active, status=state.status)
    kept = tuple(output for output in transition.outputs if not isinstance(output, outs.PublishStatus))
    return Transition(after, kept)


#: The step rules that decide something, each switched off by not deciding it (what the server does
#: instead, and the machine's attributes replaced); every other step rule is switched off by
#: dropping the outputs the machine gives under it.
DECISIONS: Mapping[str, tuple[str, Callable[[], Mapping[str, Any]], Rewrite | None]] = {
    "R3.1": ("a begin leaves the seq as it was", lambda: {"next_seq": lambda seq: seq}, None),
    "R5.2": ("a goal starts without the world checked again", lambda: {"race_lost": lambda *_: ""}, None),
    "R6.1": (
        "a NEXT starts without its description checked again",
        lambda: {"_DESCRIPTION_CHECKS": ()},
        None,
    ),
    "R8.1": (
        "a child's end is answered with a result that names neither it nor its status",
        dict,
        _no_child_in_result,
    ),
    "R8.4": ("no status is published when a child ends", dict, _child_end_unpublished),
    "R12.2": ("a stubborn period below the minimum is clamped without the warning", dict, _unwarned_clamp),
    "R13.4": (
        "a child that ends under a task signal ends as any child does: the run goes on",
        lambda: {"_BY_CLASS": _handler(ins.ChildFinished, _signal_forgotten)},
        None,
    ),
    "R15.2": (
        "a shutdown aborts the goals and leaves the dynamic event active",
        lambda: {"_BY_CLASS": _handler(ins.Shutdown, _still_active)},
        None,
    ),
    "R17.1": (
        "rmf_ros2 mode checks what R17.1 leaves out, as the standard mode does",
        lambda: {"_RMF_ROS2_WALKS": machine._STANDARD_WALKS},
        None,
    ),
}


def _step_switch(rule: str) -> Switch:
    if rule in DECISIONS:
        how, patches, rewrite = DECISIONS[rule]
        return Switch(rule, "step", how, dict(patches()), rewrite)
    how = f"the outputs the machine gives under {rule} are dropped"
    return Switch(rule, "step", how, rewrite=_dropped(rule))


@functools.cache
def switch(rule: str) -> Switch:
    """The switch of ``rule``, a request check's or a step's; ``KeyError`` for a rule the machine
    does not carry out."""
    if rule in check_rules():
        return _without_check(rule)
    if rule in step_rules():
        return _step_switch(rule)
    raise KeyError(rule)


def switches() -> list[Switch]:
    """Every check of the machine, switched off: its request checks, then its step rules."""
    return [switch(rule) for rule in (*check_rules(), *step_rules())]


# ------------------------------------------------------------------ servers


@contextlib.contextmanager
def switched_off(rule: str) -> Iterator[None]:
    """The machine with ``rule`` switched off while the block runs (one thread: the machine's module
    attributes are replaced, then put back)."""
    chosen = switch(rule)
    patches = dict(chosen.patches)
    if chosen.rewrite is not None:
        rewrite, step = chosen.rewrite, machine.step

        def rewritten(state: State, event: ins.Input, config: ServerConfig) -> Transition:
            transition = step(state, event, config)
            changed = (rewrite(event, output) for output in transition.outputs)
            return Transition(transition.state, tuple(output for output in changed if output is not None))

        patches["step"] = rewritten
    with patched(patches):
        yield


def switched_off_stepper(
    step: Callable[[ins.Input], Sequence[outs.Output]], rule: str
) -> Callable[[ins.Input], tuple[outs.Output, ...]]:
    """``step`` (a server's, :meth:`dynevent.server.holder.RobotServer.step` say) with ``rule`` switched
    off while it steps: the server of the in-process probe."""

    def stepped(event: ins.Input) -> tuple[outs.Output, ...]:
        with switched_off(rule):
            return tuple(step(event))

    return stepped


def switched_off_implementation(implementation: Any, rule: str) -> Any:
    """``implementation``, of the driver protocol and in this process (the vectors' runner's
    ``InProcessImplementation``, say), with every request run with ``rule`` switched off: the server
    of the vectors, and of the probe's driver link."""
    return _SwitchedOffImplementation(implementation, rule)


class _SwitchedOffImplementation:
    """What :func:`switched_off_implementation` gives."""

    def __init__(self, implementation: Any, rule: str) -> None:
        self._implementation = implementation
        self._rule = rule
        self.name = f"{implementation.name}, {rule} switched off"

    def reset(self, fleet: str, robot: str, config: Any, state: Any) -> None:
        with switched_off(self._rule):
            self._implementation.reset(fleet, robot, config, state)

    def apply(self, event: Any) -> tuple[list[Any], Any]:
        with switched_off(self._rule):
            result: tuple[list[Any], Any] = self._implementation.apply(event)
        return result

    def close(self) -> None:
        self._implementation.close()
