"""One oracle: a protocol fact is written once, in the machine (src/dynevent/server/machine.py) or the
vocabulary (src/dynevent/wire/vocab.py), and every judge asks them.

These tests fail when a judge keeps a copy: a status, reason, failure or task-signal text typed
again outside those two files, the child's final statuses read outside them (R20.2 is the
machine's), or the order of the request checks rebuilt from the declaration order of the reasons.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from dynevent.wire.vocab import TASK_SIGNAL_LOGS, Failure, RejectReason, Status

SRC = Path(__file__).resolve().parents[2] / "src" / "dynevent"
HOMES = frozenset({"wire/vocab.py", "server/machine.py"})

#: Protocol words typed where they mean something else: each (file, text) with why.
NOT_THE_PROTOCOL: dict[tuple[str, str], str] = {
    ("client/outputs.py", "completed"): "OutcomeKind's own value, mapped from Status",
    ("client/outputs.py", "canceled"): "OutcomeKind's own value",
    ("client/outputs.py", "killed"): "OutcomeKind's own value",
    ("client/outputs.py", "skipped"): "OutcomeKind's own value",
    ("client/outputs.py", "failed"): "OutcomeKind's own value",
    ("client/outputs.py", "error"): "OutcomeKind's own value",
    ("conformance/vectors/driver.py", "error"): "the driver protocol's JSON key",
    ("conformance/vectors/runner.py", "error"): "the driver protocol's JSON key",
    ("conformance/vectors/report.py", "failed"): "a report's tally and JUnit attribute",
    ("conformance/vectors/report.py", "skipped"): "JUnit's element",
    ("conformance/probe/cases.py", "skipped"): "JUnit's element",
    ("server/resync.py", "queued"): "a function's name in __all__",
}


def _protocol_texts() -> dict[str, str]:
    texts = {status.value: "a status" for status in Status}
    texts.update({reason.value: "a reject reason" for reason in RejectReason})
    texts.update({failure.value: "a failure string" for failure in Failure})
    texts.update({text: "a task signal's log" for text in TASK_SIGNAL_LOGS.values()})
    return texts


def _modules() -> list[tuple[str, ast.Module]]:
    found = []
    for path in sorted(SRC.rglob("*.py")):
        relative = path.relative_to(SRC).as_posix()
        if relative not in HOMES:
            found.append((relative, ast.parse(path.read_text(encoding="utf-8"))))
    return found


def _docstrings(tree: ast.Module) -> set[int]:
    owners = (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)
    return {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, owners)
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }


def protocol_texts_outside_the_oracle(modules: list[tuple[str, ast.Module]]) -> list[str]:
    texts = _protocol_texts()
    found = []
    for relative, tree in modules:
        docs = _docstrings(tree)
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Constant) and isinstance(node.value, str)) or id(node) in docs:
                continue
            if node.value in texts and (relative, node.value) not in NOT_THE_PROTOCOL:
                found.append(f"{relative}:{node.lineno}: {node.value!r} is {texts[node.value]}")
    return found


def rule_logic_outside_the_oracle(modules: list[tuple[str, ast.Module]]) -> list[str]:
    found = []
    for relative, tree in modules:
        for node in ast.walk(tree):
            if isinstance(node, ast.Name) and node.id == "ENDED_CHILD_STATUSES":
                found.append(f"{relative}:{node.lineno}: reads the final statuses (R20.2: ask the machine)")
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Name)
                and node.func.id == "enumerate"
                and any(isinstance(arg, ast.Name) and arg.id == "RejectReason" for arg in node.args)
            ):
                found.append(
                    f"{relative}:{node.lineno}: orders the reasons (R4: REQUEST_CHECKS is the order)"
                )
    return found


#: Where the final statuses are read for another purpose than R20.2, with why.
FINAL_STATUS_READERS = {
    "conformance/judge/observer.py": "a child's final status guessed for an answer the recording lacks",
}


def test_no_protocol_text_is_typed_outside_the_machine_and_the_vocabulary() -> None:
    assert protocol_texts_outside_the_oracle(_modules()) == []


def test_no_rule_is_worked_out_again_outside_the_machine() -> None:
    found = [
        line
        for line in rule_logic_outside_the_oracle(_modules())
        if not (line.split(":")[0] in FINAL_STATUS_READERS and "R20.2" in line)
    ]
    assert found == []
    for relative in FINAL_STATUS_READERS:
        assert any(line.startswith(relative) for line in rule_logic_outside_the_oracle(_modules())), (
            f"{relative} no longer reads the final statuses: take it off the list"
        )


@pytest.mark.parametrize(
    ("source", "kind"),
    [
        ('def waits(s):\n    return s.status != "standby"\n', "a status"),
        ('LOGS = {"Received signal to cancel": 1}\n', "a task signal's log"),
        ("ORDER = {r: i for i, r in enumerate(RejectReason)}\n", "orders the reasons"),
        ("def ended(s):\n    return s.status in ENDED_CHILD_STATUSES\n", "final statuses"),
    ],
)
def test_the_scan_sees_a_copy(source: str, kind: str) -> None:
    modules = [("ros/judge.py", ast.parse(source))]
    found = protocol_texts_outside_the_oracle(modules) + rule_logic_outside_the_oracle(modules)
    assert len(found) == 1 and kind in found[0]
