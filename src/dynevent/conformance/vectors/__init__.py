"""Conformance vectors: load them, run them against an implementation, report.

A vector is a scripted exchange written from docs/spec.md: a server
configuration, an initial state, and steps, each an input and the exact
outputs the spec requires in answer (and optionally the phase, seq and current
id after it).  The vectors ship with the package (in this folder,
``dynevent/conformance/vectors/``,
one JSON file per spec section, with the JSON Schema ``vector.schema.json``)
and run against dynevent in process or against any program that speaks the
driver protocol of :mod:`dynevent.conformance.vectors.driver`.

This module is the one to import; the work is done in four parts:
:mod:`~dynevent.conformance.vectors.files` (the vector model and its files),
:mod:`~dynevent.conformance.vectors.diff` (matching, and where a mismatch lies),
:mod:`~dynevent.conformance.vectors.runner` (implementations and running, robust to a
misbehaving driver) and :mod:`~dynevent.conformance.vectors.report` (text, JSON, JUnit).

Matching is exact, except that the string ``"*"`` in an expected output
matches any string (for sentences whose wording the spec leaves open).
"""

from __future__ import annotations

from dynevent.conformance.vectors.diff import (
    MAX_DIFFERENCES,
    MAX_KEPT_VALUE,
    WILDCARD,
    Difference,
    align,
    differences,
    matches,
)
from dynevent.conformance.vectors.files import (
    SCHEMA_FILE,
    Step,
    Vector,
    load_vectors,
    parse_vector_file,
    schema_problem,
    schema_validation_available,
    select_vectors,
)
from dynevent.conformance.vectors.report import (
    WIDTH,
    RuleTally,
    format_report,
    junit_xml,
    outcome_record,
    rule_table,
    summary_record,
    took_line,
)
from dynevent.conformance.vectors.runner import (
    MAX_ANSWER_BYTES,
    MAX_BROKEN,
    MAX_STALLS,
    MAX_TIMEOUT,
    START_TIMEOUT,
    ExternalImplementation,
    Failure,
    Implementation,
    InProcessImplementation,
    Outcome,
    run_vector,
    run_vectors,
)
from dynevent.errors import ImplementationError, ImplementationGone, InvalidVector

__all__ = [
    "MAX_ANSWER_BYTES",
    "MAX_BROKEN",
    "MAX_DIFFERENCES",
    "MAX_KEPT_VALUE",
    "MAX_STALLS",
    "MAX_TIMEOUT",
    "SCHEMA_FILE",
    "START_TIMEOUT",
    "WIDTH",
    "WILDCARD",
    "Difference",
    "ExternalImplementation",
    "Failure",
    "Implementation",
    "ImplementationError",
    "ImplementationGone",
    "InProcessImplementation",
    "InvalidVector",
    "Outcome",
    "RuleTally",
    "Step",
    "Vector",
    "align",
    "differences",
    "format_report",
    "junit_xml",
    "load_vectors",
    "matches",
    "outcome_record",
    "parse_vector_file",
    "rule_table",
    "run_vector",
    "run_vectors",
    "schema_problem",
    "schema_validation_available",
    "select_vectors",
    "summary_record",
    "took_line",
]
