"""docs/spec.md stays true: every rule cited by a test, every citation a rule, the diagram current."""

from __future__ import annotations

import re
from pathlib import Path

from dynevent.tools.diagram import render

ROOT = Path(__file__).resolve().parents[1]
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
