"""Judging what a server did, from what was seen of it: the observer every judge feeds.

A judge takes :class:`Record` values one at a time, in the server's order (:meth:`Judge.push`), and
gives a :class:`Report` of :class:`Finding` values at the end (:meth:`Judge.finish`); each finding
names the docs/spec.md rule it breaks.  Two judges keep that interface:

- :class:`Checker` (:mod:`.observer`), for a view that holds the goals and their answers (a trace,
  a recording with the action's introspection, what a probe case saw): it keeps a server state of
  the machine (:mod:`dynevent.server.machine`) and infers the server's inputs from what it sees,
  so every expectation is the machine's own (:mod:`.abduction` says how an input is inferred);
- :class:`PartialJudge` (:mod:`.partial`), for a view of the topics alone (statuses, begins,
  feedback, goal statuses): what they show is judged, and what they cannot show is not guessed.

Traces (docs/trace-format.md) are read and written by :mod:`.trace`; :func:`check_trace` judges
one; recordings are read into records by :mod:`dynevent.bags`.  ``dynevent check``, ``dynevent
probe``, serve's judgement of its clients and the test kit all judge through here, so a scripted
verdict and a passive one can never disagree.

Beside the judges: :mod:`.replay` drives the machine with a recording's inputs and sets what it says
beside what the server said (:mod:`.divergences` labels the judge's findings on rmf_ros2 with it),
and :mod:`.clients` judges a server's clients (section 22) for ``dynevent serve``.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, Protocol

import attrs

from dynevent.conformance.judge.observer import AnswerEvidence, Checker, check_records
from dynevent.conformance.judge.partial import PartialJudge
from dynevent.conformance.judge.trace import (
    RECORD_TYPES,
    Finding,
    Record,
    Report,
    TraceWriter,
    read_trace,
    step_records,
    stream_trace,
)
from dynevent.errors import TraceError
from dynevent.wire.vocab import Compatibility

__all__ = [
    "RECORD_TYPES",
    "AnswerEvidence",
    "Checker",
    "Finding",
    "Judge",
    "PartialJudge",
    "Record",
    "Report",
    "TraceError",
    "TraceWriter",
    "check_records",
    "check_trace",
    "format_report",
    "read_trace",
    "step_records",
    "stream_trace",
    "trace_records",
]


class Judge(Protocol):
    """What every judge is: records in, one at a time in the server's order; a report at the end."""

    def push(self, record: Record) -> None:
        """Judge the next record."""

    def finish(self) -> Report:
        """The findings of every record pushed."""


def check_trace(
    text: str | Iterable[str],
    source: str = "<trace>",
    *,
    compatibility: Compatibility | str = Compatibility.STANDARD,
) -> Report:
    """Check a trace (its text, or its lines) in observer mode; each violation is a :class:`Finding`.

    ``compatibility="rmf_ros2"`` judges the server as ``dynevent serve --compatibility rmf_ros2``
    behaves (R17, and the adapter's own numbering of children), where the trace has no config record
    that says otherwise: what is left is where the server differs from that emulation.  Raises
    :class:`TraceError` (naming ``source``, the line and the field) when the trace cannot be read.
    """
    lines = text.splitlines() if isinstance(text, str) else text
    header, records = stream_trace(lines, source)
    header = attrs.evolve(header, compatibility=Compatibility(compatibility))
    return check_records(header, records, source)


def format_report(report: Report) -> str:
    """The findings as text, one per line with what was expected, then a summary line."""
    lines = []
    for finding in report.findings:
        lines.append(f"{report.source}:{finding.line}: {finding.rule} {finding.code}: {finding.message}")
        lines.append(f"    expected: {finding.expected}")
    count = len(report.findings)
    noun = "violation" if count == 1 else "violations"
    summary = f"{report.source}: {report.records} records, {count or 'no'} {noun}"
    lines.append(summary)
    return "\n".join(lines) + "\n"


def trace_records(report: Report) -> list[dict[str, Any]]:
    """The JSON lines of ``dynevent check --json``: one object per finding, then a summary."""
    rows: list[dict[str, Any]] = [
        {"type": "violation", "file": report.source, **finding.to_dict()} for finding in report.findings
    ]
    rows.append(
        {
            "type": "summary",
            "file": report.source,
            "records": report.records,
            "violations": len(report.findings),
        }
    )
    return rows
