"""What a run of the vectors says: the text report, the JSON records and a JUnit XML file.

The text report keeps within :data:`WIDTH` columns (long values are cut; the
JSON records keep them whole).  A vector is passed, failed or not run; the
rule table counts each vector once per rule it cites.
"""

from __future__ import annotations

import textwrap
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Sequence
from typing import Any

import attrs

from dynevent.conformance.vectors.files import rule_key
from dynevent.conformance.vectors.runner import Outcome
from dynevent.conformance.vectors.xml_report import xml_document

__all__ = [
    "WIDTH",
    "RuleTally",
    "format_report",
    "junit_xml",
    "outcome_record",
    "rule_table",
    "summary_record",
    "took_line",
]

#: The widest line of the text report.
WIDTH = 100


@attrs.frozen
class RuleTally:
    """How the vectors citing one rule fared."""

    rule: str
    vectors: int
    passed: int
    not_run: int = 0

    @property
    def failed(self) -> int:
        """Vectors citing the rule that failed."""
        return self.vectors - self.passed - self.not_run


def rule_table(outcomes: Iterable[Outcome]) -> list[RuleTally]:
    """One tally per cited rule, in rule order."""
    counts: dict[str, list[int]] = {}
    for outcome in outcomes:
        for rule in dict.fromkeys(outcome.vector.rules):
            tally = counts.setdefault(rule, [0, 0, 0])
            tally[0] += 1
            tally[1] += outcome.passed
            tally[2] += outcome.not_run is not None
    return [
        RuleTally(rule, total, passed, not_run)
        for rule, (total, passed, not_run) in sorted(counts.items(), key=lambda item: rule_key(item[0]))
    ]


def _counts(outcomes: Sequence[Outcome]) -> tuple[int, int, int]:
    passed = sum(outcome.passed for outcome in outcomes)
    not_run = sum(outcome.not_run is not None for outcome in outcomes)
    return passed, len(outcomes) - passed - not_run, not_run


def format_report(outcomes: Sequence[Outcome], implementation: str = "") -> str:
    """The human report: the table by rule, an account per failed vector, then
    ``N passed, M failed`` (and ``, K not run`` with the reason, when the run stopped early)."""
    lines = [f"implementation: {implementation}"[:WIDTH]] if implementation else []
    table = rule_table(outcomes)
    width = max([len("rule"), *(len(tally.rule) for tally in table)])
    stopped = any(tally.not_run for tally in table)  # a "not run" column only when the run stopped early
    lines.append(f"{'rule':<{width}}  {'vectors':>7}  {'passed':>6}  {'failed':>6}" + ("  not run" * stopped))
    for tally in table:
        row = f"{tally.rule:<{width}}  {tally.vectors:>7}  {tally.passed:>6}  {tally.failed:>6}"
        row += f"  {tally.not_run:>7}" * stopped
        lines.append(row + ("  FAIL" if tally.failed else ""))
    for outcome in outcomes:
        if outcome.failure is None:
            continue
        vector = outcome.vector
        lines.append("")
        lines.append(f"FAIL {vector.name} ({vector.source})"[:WIDTH])
        lines.extend(
            textwrap.wrap(
                ", ".join(vector.rules), WIDTH, initial_indent="  rules: ", subsequent_indent="         "
            )
        )
        if vector.summary:
            lines.extend(textwrap.wrap(vector.summary, WIDTH, initial_indent="  ", subsequent_indent="  "))
        lines.extend(f"  {line}" for line in outcome.failure.diff(WIDTH - 2).splitlines())
    passed, failed, not_run = _counts(outcomes)
    lines.append("")
    if not_run:
        reason = next(outcome.not_run for outcome in outcomes if outcome.not_run is not None)
        lines.extend(textwrap.wrap(f"{not_run} not run: {reason}", WIDTH, subsequent_indent="  "))
        lines.append(f"{passed} passed, {failed} failed, {not_run} not run")
    else:
        lines.append(f"{passed} passed, {failed} failed")
    return "\n".join(lines)


def outcome_record(outcome: Outcome) -> dict[str, Any]:
    """One vector's result as a JSON object (``dynevent vectors --json``)."""
    vector, failure = outcome.vector, outcome.failure
    return {
        "type": "vector",
        "name": vector.name,
        "source": vector.source,
        "rules": list(vector.rules),
        "summary": vector.summary,
        "passed": outcome.passed,
        "not_run": outcome.not_run,
        "failure": None
        if failure is None
        else {
            "step": failure.step,
            "problem": failure.problem,
            "input": failure.input,
            "expected": failure.expected,
            "got": failure.got,
            "differences": [difference.record() for difference in failure.differences],
            "more_differences": failure.more_differences,
            "diff": failure.diff(WIDTH),
        },
    }


def summary_record(
    outcomes: Sequence[Outcome], implementation: str = "", *, seconds: float | None = None
) -> dict[str, Any]:
    """The closing JSON object of ``dynevent vectors --json`` (``seconds``: what the run took, when
    given)."""
    passed, failed, not_run = _counts(outcomes)
    record: dict[str, Any] = {
        "type": "summary",
        "implementation": implementation,
        "vectors": len(outcomes),
        "passed": passed,
        "failed": failed,
        "not_run": not_run,
        "rules": {
            tally.rule: {
                "vectors": tally.vectors,
                "passed": tally.passed,
                "failed": tally.failed,
                "not_run": tally.not_run,
            }
            for tally in rule_table(outcomes)
        },
    }
    if seconds is not None:
        record["seconds"] = round(seconds, 3)
    return record


def took_line(seconds: float, bound: str = "") -> str:
    """The last line of a run of the vectors or of the probe: what it took in real time, and the
    bound it ran within when it has one (``bound``: ``"--deadline 120 s"``)."""
    return f"the run took {seconds:.1f} s" + (f" ({bound})" if bound else "")


def junit_xml(outcomes: Sequence[Outcome], implementation: str = "") -> str:
    """The run as JUnit XML, as CI systems read it: one test suite, one test case per vector
    (``classname`` the vector file, ``name`` the vector), a failure with the account of the
    mismatch, a skip for a vector not run; each case's rules as a property."""
    _, failed, not_run = _counts(outcomes)
    suites = ET.Element(
        "testsuites",
        name="dynevent vectors",
        tests=str(len(outcomes)),
        failures=str(failed),
        skipped=str(not_run),
    )
    suite = ET.SubElement(
        suites,
        "testsuite",
        name=implementation or "dynevent vectors",
        tests=str(len(outcomes)),
        failures=str(failed),
        errors="0",
        skipped=str(not_run),
    )
    for outcome in outcomes:
        vector = outcome.vector
        case = ET.SubElement(suite, "testcase", classname=vector.source, name=vector.name)
        properties = ET.SubElement(case, "properties")
        ET.SubElement(properties, "property", name="rules", value=" ".join(vector.rules))
        if outcome.failure is not None:
            problem = f"step {outcome.failure.step}: {outcome.failure.problem}"
            element = ET.SubElement(case, "failure", message=problem, type="mismatch")
            element.text = outcome.failure.diff(WIDTH)
        elif outcome.not_run is not None:
            ET.SubElement(case, "skipped", message=outcome.not_run)
    return xml_document(suites)
