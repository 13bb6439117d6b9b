"""docs/spec.md stays true: every rule cited by a test, every citation a rule, the diagram current."""

from __future__ import annotations

import ast
import os
import re
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


# --------------------------------------------------------------------------- where each rule is carried out

SRC = ROOT / "src" / "dynevent"
#: Where the rules are carried out: the library.  Left out are the judges, the probe and the kit
#: (conformance/, testing/), which check rules, the tools and simulations that use the library
#: (tools/, sim/, bags/), and wire/vocab.py, which names the words of every rule.
NOT_CARRIERS = ("conformance/", "testing/", "tools/", "sim/", "bags/", "wire/vocab.py")

#: The rules that no place of the library cites: where they are carried out, or why nothing does.
ELSEWHERE = {
    "R19.1": "every handler together (each goal answered once: R5, R8 to R11, R15.1, R21.1); "
    "tests/spec/test_19_invariants.py holds it over generated runs, and `conformance.judge.observer` "
    "judges it on every record",
    **{
        rule: "a rule on what a client sends: a server refuses such a goal by R4 whoever sent it, and "
        "`conformance.judge.clients.ClientJudge` (`dynevent check`) names the client that breaks it"
        for rule in ("R22.2", "R22.3", "R22.4", "R22.5", "R22.6")
    },
    "R22.8": "a rule on clients: no server can make a client end the run it drove, and "
    "`conformance.judge.clients.ClientJudge.close` (`dynevent check`) names the client that left it open",
}


def _carried_out() -> dict[str, dict[str, list[str]]]:
    """Rule -> module -> the top-level functions, classes and tables of the library that cite the rule
    (in their text, or the ``#:``/``#`` comment lines just above them)."""
    where: dict[str, dict[str, list[str]]] = {}
    for path in sorted(SRC.glob("**/*.py")):
        relative = path.relative_to(SRC).as_posix()
        if relative.startswith(NOT_CARRIERS):
            continue
        module = relative.removesuffix(".py").removesuffix("/__init__").replace("/", ".")
        source = path.read_text(encoding="utf-8")
        lines = source.split("\n")
        for node in ast.parse(source).body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                name = node.name
            elif isinstance(node, (ast.Assign, ast.AnnAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                name = next((target.id for target in targets if isinstance(target, ast.Name)), "")
            else:
                continue
            if not name:
                continue
            first = min(
                [node.lineno] + [decorator.lineno for decorator in getattr(node, "decorator_list", [])]
            )
            while first > 1 and lines[first - 2].startswith("#") and not lines[first - 2].startswith("# --"):
                first -= 1
            text = "\n".join(lines[first - 1 : node.end_lineno])
            for rule in dict.fromkeys(re.findall(r"\bR\d+\.\d+\b", text)):
                where.setdefault(rule, {}).setdefault(module, []).append(name)
    return where


def _places(rule: str, where: dict[str, dict[str, list[str]]]) -> str:
    if rule not in where:
        return ELSEWHERE.get(rule, "")
    return "; ".join(
        f"`{module}`: " + ", ".join(f"`{name}`" for name in names) for module, names in where[rule].items()
    )


def rule_index() -> str:
    """docs/rule-index.md as the code, the tests and the vectors make it now."""
    from dynevent.conformance.vectors import load_vectors

    tests = _tests_by_rule()
    where = _carried_out()
    vectors: dict[str, list[str]] = {}
    for vector in load_vectors():
        for rule in vector.rules:
            vectors.setdefault(rule, []).append(vector.source.rsplit("/", 1)[-1])
    lines = [
        "# Every rule: where it is carried out, and what checks it",
        "",
        "One index for the whole project, generated: `DYNEVENT_UPDATE_RULE_INDEX=1 pytest",
        "tests/project/test_spec_document.py` rewrites it, and that test fails while it is stale.  Rules",
        "are those of [spec.md](spec.md).",
        "",
        "- **carried out in**: the top-level functions, classes and tables of the library",
        "  (`src/dynevent`, module by module) that cite the rule, in their text or the comment just",
        "  above them.  The judges, the probe and the test kit (`conformance/`, `testing/`), which check",
        "  rules, the tools and simulations that use the library, and `wire/vocab.py`, which names",
        "  every rule's words, are left out.  A rule no place of the library cites says where it is",
        "  carried out instead (the list `ELSEWHERE` of the test).",
        "- **tests**: the tests' `@pytest.mark.spec(...)` marks; **vectors**: the conformance vectors'",
        "  `rules` (src/dynevent/conformance/vectors/*.json).",
        "",
        "| rule | carried out in | tests | vectors |",
        "|---|---|---|---|",
    ]
    for rule in sorted(RULES, key=_rule_key):
        cited = ", ".join(f"`{test}`" for test in tests.get(rule, []))
        files = vectors.get(rule, [])
        counted = ", ".join(f"{source} ({files.count(source)})" for source in dict.fromkeys(files))
        lines.append(f"| {rule} | {_places(rule, where)} | {cited} | {counted} |")
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


def test_every_rule_is_carried_out_somewhere_the_index_names() -> None:
    where = _carried_out()
    unknown = sorted(set(where) - RULES, key=_rule_key)
    assert not unknown, f"the code cites rules that docs/spec.md does not define: {unknown}"
    nowhere = sorted(RULES - set(where) - set(ELSEWHERE), key=_rule_key)
    assert not nowhere, f"rules no code cites and ELSEWHERE does not place: {nowhere}"
    stale = sorted(set(ELSEWHERE) & set(where), key=_rule_key)
    assert not stale, f"ELSEWHERE places rules the code now cites: {stale}"
    assert set(ELSEWHERE) <= RULES
    machine = {rule for rule, modules in where.items() if "server.machine" in modules}
    assert {"R4.2", "R8.4", "R12.2", "R19.3", "R20.2"} <= machine
    assert "_seq_mismatch" in where["R4.2"]["server.machine"]
    assert "ros.server" in where["R22.1"] and "server.snapshot" in where["R19.8"]


def test_machine_py_points_to_the_one_index_and_holds_no_copy() -> None:
    note = ast.get_docstring(ast.parse((SRC / "server" / "machine.py").read_text(encoding="utf-8")))
    assert note is not None and "docs/rule-index.md" in note
    assert not re.search(r"^\s+R\d+\.\d+\s", note, re.MULTILINE), "machine.py holds a second index"
