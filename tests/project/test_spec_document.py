"""docs/spec.md stays true: every rule cited by a test, every citation a rule, the diagram current."""

from __future__ import annotations

import ast
import os
import re
import textwrap
from pathlib import Path

from dynevent.tools.diagram import render

ROOT = Path(__file__).resolve().parents[2]
SPEC = (ROOT / "docs" / "spec.md").read_text(encoding="utf-8")
RULES = set(re.findall(r"\*\*(R\d+\.\d+)\*\*", SPEC))


def _cited() -> set[str]:
    cited: set[str] = set()
    for path in (ROOT / "tests").glob("**/*.py"):
        for call in re.findall(r"spec\(([^)]*)\)", path.read_text(encoding="utf-8")):
            cited.update(re.findall(r"R\d+\.\d+", call))
    return cited


def test_rules_are_numbered_in_order() -> None:
    numbers = [
        tuple(int(part) for part in rule[1:].split(".")) for rule in re.findall(r"\*\*(R\d+\.\d+)\*\*", SPEC)
    ]
    assert numbers == sorted(numbers)
    assert len(numbers) == len(set(numbers)), "a rule number is defined twice"


def test_every_rule_has_a_test() -> None:
    missing = sorted(RULES - _cited(), key=lambda rule: tuple(int(part) for part in rule[1:].split(".")))
    assert not missing, f"rules without a citing test: {missing}"


def test_every_citation_names_a_rule() -> None:
    unknown = sorted(_cited() - RULES)
    assert not unknown, f"tests cite rules that docs/spec.md does not define: {unknown}"


def test_embedded_diagram_is_current() -> None:
    block = SPEC.split("<!-- diagram:start -->\n", 1)[1].split("<!-- diagram:end -->", 1)[0]
    assert block == f"```mermaid\n{render('mermaid')}```\n"


# --------------------------------------------------------------------------- the rule -> tests index

INDEX = ROOT / "docs" / "rule-index.md"


def _rule_key(rule: str) -> tuple[int, ...]:
    return tuple(int(part) for part in rule[1:].split("."))


def _spec_rules(node: ast.AST) -> list[str]:
    """The rules a ``pytest.mark.spec(...)`` decorator or assignment names."""
    rules: list[str] = []
    for call in ast.walk(node):
        if (
            isinstance(call, ast.Call)
            and isinstance(call.func, ast.Attribute)
            and call.func.attr == "spec"
            and isinstance(call.func.value, ast.Attribute)
            and call.func.value.attr == "mark"
        ):
            rules.extend(arg.value for arg in call.args if isinstance(arg, ast.Constant))
    return rules


def _tests_by_rule() -> dict[str, list[str]]:
    found: dict[str, list[str]] = {}
    for path in sorted((ROOT / "tests").glob("**/test_*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        name = path.relative_to(ROOT / "tests").as_posix()
        module_rules = [
            rule
            for node in tree.body
            if isinstance(node, ast.Assign)
            and any(isinstance(target, ast.Name) and target.id == "pytestmark" for target in node.targets)
            for rule in _spec_rules(node.value)
        ]
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and node.name.startswith(("test_", "Test")):
                rules = [rule for decorator in node.decorator_list for rule in _spec_rules(decorator)]
                for rule in dict.fromkeys(
                    rules + (module_rules if isinstance(node, ast.FunctionDef) else [])
                ):
                    found.setdefault(rule, []).append(f"{name}::{node.name}")
    return found


def rule_index() -> str:
    """docs/rule-index.md as the tests and the vectors make it now."""
    from dynevent.conformance.vectors import load_vectors

    tests = _tests_by_rule()
    vectors: dict[str, list[str]] = {}
    for vector in load_vectors():
        for rule in vector.rules:
            vectors.setdefault(rule, []).append(vector.source.rsplit("/", 1)[-1])
    lines = [
        "# Every rule and what checks it",
        "",
        "Generated from the tests' `@pytest.mark.spec(...)` marks and the conformance vectors'",
        "`rules`; `DYNEVENT_UPDATE_RULE_INDEX=1 pytest tests/project/test_spec_document.py` rewrites it, and",
        "that test fails while it is stale.  Rules are those of [spec.md](spec.md).",
        "",
        "| rule | tests | vectors |",
        "|---|---|---|",
    ]
    for rule in sorted(RULES, key=_rule_key):
        cited = ", ".join(f"`{test}`" for test in tests.get(rule, []))
        files = vectors.get(rule, [])
        counted = ", ".join(f"{source} ({files.count(source)})" for source in dict.fromkeys(files))
        lines.append(f"| {rule} | {cited} | {counted} |")
    return "\n".join(lines) + "\n"


def test_the_rule_index_is_current() -> None:
    text = rule_index()
    if os.environ.get("DYNEVENT_UPDATE_RULE_INDEX") == "1":
        INDEX.write_text(text, encoding="utf-8")
    how = "DYNEVENT_UPDATE_RULE_INDEX=1 pytest tests/project/test_spec_document.py"
    assert INDEX.read_text(encoding="utf-8") == text, f"docs/rule-index.md is stale: {how}"


def test_the_rule_index_reads_module_and_function_marks() -> None:
    tests = _tests_by_rule()
    assert "wire/test_names.py::test_valid_tokens" in tests["R1.4"]  # marked by the module's pytestmark
    assert "ros/test_ros_serve.py::test_a_foreign_state_file_is_refused_and_left_as_it_was" not in str(tests)
    assert set(tests) == _cited()  # the index's reading of the marks agrees with the citations found


# --------------------------------------------------------------------------- the machine's own index

SERVER = ROOT / "src" / "dynevent" / "server"
#: The files of the rules: the machine, and the configuration and state types beside it.
RULE_FILES = ("machine.py", "config.py", "state.py")
INDEX_START = "Where each rule is carried out"
INDEX_END = '"""'


def machine_rule_index() -> str:
    """The module docstring's index of machine.py: each rule cited in the rule files, and the top-level
    functions, classes and constants that cite it (of config.py and state.py, named with their module)."""
    where: dict[str, list[str]] = {}
    for file in RULE_FILES:
        source = (SERVER / file).read_text(encoding="utf-8")
        lines = source.split("\n")
        for node in ast.parse(source).body:
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                name = node.name
            elif isinstance(node, (ast.Assign, ast.AnnAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                name = next((target.id for target in targets if isinstance(target, ast.Name)), "")
            else:
                continue
            if not name:
                continue
            text = "\n".join(lines[node.lineno - 1 : node.end_lineno])
            label = name if file == "machine.py" else f"{file.removesuffix('.py')}.{name}"
            for rule in dict.fromkeys(re.findall(r"\bR\d+\.\d+\b", text)):
                where.setdefault(rule, []).append(label)
    rows = [
        f"{INDEX_START} (the functions, classes and tables that cite it; those of",
        ":mod:`dynevent.server.config` and :mod:`dynevent.server.state` named with their module).",
        "``DYNEVENT_UPDATE_RULE_INDEX=1 pytest tests/project/test_spec_document.py`` rewrites it from the",
        "citations, and that test fails while it is stale::",
        "",
    ]
    for rule in sorted(where, key=_rule_key):
        rows.extend(textwrap.wrap(", ".join(where[rule]), 100, initial_indent=f"    {rule:<7}",
                                  subsequent_indent=" " * 11, break_on_hyphens=False))  # fmt: skip
    return "\n".join(rows) + "\n"


def test_the_machine_names_where_each_rule_is_carried_out() -> None:
    path = SERVER / "machine.py"
    source = path.read_text(encoding="utf-8")
    start = source.index(INDEX_START)
    end = source.index(INDEX_END, start)
    expected = machine_rule_index()
    if os.environ.get("DYNEVENT_UPDATE_RULE_INDEX") == "1":
        path.write_text(source[:start] + expected + source[end:], encoding="utf-8")
        return
    how = "DYNEVENT_UPDATE_RULE_INDEX=1 pytest tests/project/test_spec_document.py"
    assert source[start:end] == expected, f"machine.py's rule index is stale: {how}"
    cited = {line.split()[0] for line in expected.splitlines() if line.startswith("    R")}
    assert cited <= RULES, sorted(cited - RULES)  # every rule the machine cites is one of the spec's
    assert {"R4.2", "R8.4", "R12.2", "R20.2"} <= cited
