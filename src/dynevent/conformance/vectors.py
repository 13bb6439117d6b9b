"""Conformance vectors: load them, run them against an implementation, report.

A vector is a scripted exchange written from docs/spec.md: a server
configuration, an initial state, and steps, each an input and the exact
outputs the spec requires in answer (and optionally the phase, seq and current
id after it).  The vectors ship with the package (``dynevent/conformance/``,
one JSON file per spec section, with the JSON Schema ``vector.schema.json``)
and run against dynevent in process or against any program that speaks the
driver protocol of :mod:`dynevent.conformance.driver`.

Matching is exact, except that the string ``"*"`` in an expected output
matches any string (for sentences whose wording the spec leaves open).
"""

from __future__ import annotations

import fnmatch
import json
import os
import re
import select
import shlex
import subprocess
import time
from collections.abc import Iterable, Iterator, Sequence
from importlib import resources
from typing import Any, Protocol

import attrs

from dynevent import __version__
from dynevent.conformance.driver import Driver
from dynevent.errors import (  # defined there with every error; importable here too
    DyneventError,
    ImplementationError,
    InvalidVector,
)
from dynevent.wire import _json

__all__ = [
    "SCHEMA_FILE",
    "WILDCARD",
    "ExternalImplementation",
    "Failure",
    "Implementation",
    "ImplementationError",
    "InProcessImplementation",
    "InvalidVector",
    "Outcome",
    "RuleTally",
    "Step",
    "Vector",
    "align",
    "format_report",
    "load_vectors",
    "matches",
    "outcome_record",
    "rule_table",
    "run_vector",
    "run_vectors",
    "schema_problem",
    "schema_validation_available",
    "select_vectors",
    "summary_record",
]

#: In an expected output, matches any string.
WILDCARD = "*"
#: The longest an external implementation may take to answer one request, in seconds.
MAX_TIMEOUT = 3600.0
#: The longest answer line an external implementation may write, in bytes.
MAX_ANSWER_BYTES = 64 * 1024 * 1024


#: The JSON Schema of a vector file, shipped beside the vectors.
SCHEMA_FILE = "vector.schema.json"


@attrs.frozen
class Step:
    """One input and what must come out of it."""

    input: Any
    expect: tuple[Any, ...]
    view: Any = None


@attrs.frozen
class Vector:
    """One conformance vector."""

    name: str
    rules: tuple[str, ...]
    divergences: tuple[str, ...]
    summary: str
    source: str
    fleet: str
    robot: str
    config: Any
    state: Any
    steps: tuple[Step, ...]


class Implementation(Protocol):
    """What the runner needs of an implementation under test."""

    def reset(self, fleet: str, robot: str, config: Any, state: Any) -> None:
        """Start a new server for one robot."""

    def apply(self, event: Any) -> tuple[list[Any], Any]:
        """Apply one input record; return the output records and the view."""

    def close(self) -> None:
        """Release the implementation."""


def _fail(answer: Any) -> ImplementationError:
    if isinstance(answer, dict) and answer.get("ok") is False:
        return ImplementationError(f"the implementation refused the request: {answer.get('error')}")
    return ImplementationError(f"malformed answer {answer!r}")


class InProcessImplementation:
    """dynevent itself, through the same driver code the external path uses."""

    def __init__(self) -> None:
        self._driver = Driver()
        self.name = f"dynevent {__version__} (in process)"

    def reset(self, fleet: str, robot: str, config: Any, state: Any) -> None:
        """Start a new server."""
        answer = self._driver.handle(
            {"op": "reset", "fleet": fleet, "robot": robot, "config": config, "state": state}
        )
        if answer.get("ok") is not True:
            raise _fail(answer)

    def apply(self, event: Any) -> tuple[list[Any], Any]:
        """Apply one input."""
        answer = self._driver.handle({"op": "apply", "input": event})
        if answer.get("ok") is not True:
            raise _fail(answer)
        # the same JSON round trip the external path makes
        answer = json.loads(_json.dumps(answer))
        return answer["outputs"], answer.get("view")

    def close(self) -> None:
        """Nothing to release."""


class ExternalImplementation:
    """An implementation run as a separate program speaking the driver protocol."""

    def __init__(self, command: str, timeout: float = 10.0) -> None:
        self.command = command
        if not (isinstance(timeout, (int, float)) and 0 < timeout <= MAX_TIMEOUT):
            raise ImplementationError(
                f"timeout: expected seconds from 0 to {MAX_TIMEOUT:g} (got {timeout!r})"
            )
        self.timeout = float(timeout)
        self._pending = b""
        try:
            words = shlex.split(command)
        except ValueError as exc:
            raise ImplementationError(f"cannot start {command!r}: {exc}") from None
        if not words:
            raise ImplementationError("the implementation's command is empty")
        try:
            self._process = subprocess.Popen(words, stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        except (OSError, ValueError) as exc:
            raise ImplementationError(f"cannot start {command!r}: {exc}") from None
        try:
            hello = self._request({"op": "hello"})
            if hello.get("ok") is not True or hello.get("protocol") != 1:
                raise ImplementationError(f"{command!r} does not speak driver protocol 1: {hello!r}")
        except ImplementationError:
            self.close()
            raise
        self.name = str(hello.get("implementation", command))

    def _request(self, request: Any) -> dict[str, Any]:
        stdin = self._process.stdin
        assert stdin is not None
        try:
            stdin.write((_json.dumps(request) + "\n").encode("utf-8"))
            stdin.flush()
        except (BrokenPipeError, OSError):
            raise ImplementationError(
                f"{self.command!r} closed its input (exit code {self._process.poll()})"
            ) from None
        raw = self._read_line()
        try:
            line = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise ImplementationError(
                f"{self.command!r} answered with bytes that are not UTF-8 ({exc.reason} "
                f"at byte {exc.start}): {raw[:200]!r}"
            ) from None
        try:
            answer = _json.parse(line)
        except _json.JsonProblem as exc:
            raise ImplementationError(f"{self.command!r} answered with {exc}: {line[:200]!r}") from None
        if not isinstance(answer, dict):
            raise _fail(answer)
        return answer

    def _read_line(self) -> bytes:
        """One answer line, within the timeout however the program writes it (a half line and a stall too)."""
        stdout = self._process.stdout
        assert stdout is not None
        deadline = time.monotonic() + self.timeout
        while b"\n" not in self._pending:
            left = deadline - time.monotonic()
            ready, _, _ = select.select([stdout], [], [], max(left, 0.0))
            if not ready:
                raise ImplementationError(f"{self.command!r} did not answer within {self.timeout:g} s")
            chunk = os.read(stdout.fileno(), 65536)
            if not chunk:
                raise ImplementationError(f"{self.command!r} ended (exit code {self._process.wait()})")
            self._pending += chunk
            if len(self._pending) > MAX_ANSWER_BYTES:
                raise ImplementationError(f"{self.command!r} answered a line above {MAX_ANSWER_BYTES} bytes")
        line, _, self._pending = self._pending.partition(b"\n")
        return line

    def reset(self, fleet: str, robot: str, config: Any, state: Any) -> None:
        """Start a new server."""
        answer = self._request(
            {"op": "reset", "fleet": fleet, "robot": robot, "config": config, "state": state}
        )
        if answer.get("ok") is not True:
            raise _fail(answer)

    def apply(self, event: Any) -> tuple[list[Any], Any]:
        """Apply one input."""
        answer = self._request({"op": "apply", "input": event})
        if answer.get("ok") is not True or not isinstance(answer.get("outputs"), list):
            raise _fail(answer)
        return answer["outputs"], answer.get("view")

    def close(self) -> None:
        """Stop the program."""
        if self._process.stdin is not None:
            self._process.stdin.close()
        try:
            self._process.wait(timeout=self.timeout)
        except subprocess.TimeoutExpired:
            self._process.kill()
            self._process.wait()
        if self._process.stdout is not None:
            self._process.stdout.close()


# --------------------------------------------------------------------------- loading


def _require(source: str, path: str, data: Any, key: str, kind: type | tuple[type, ...]) -> Any:
    if not isinstance(data, dict) or key not in data:
        raise InvalidVector(source, path, f"missing {key!r}")
    value = data[key]
    if not isinstance(value, kind) or (isinstance(value, bool) and kind is not bool):
        raise InvalidVector(source, f"{path}.{key}", f"expected {getattr(kind, '__name__', kind)}")
    return value


def _vector(source: str, path: str, data: Any) -> Vector:
    if not isinstance(data, dict):
        raise InvalidVector(source, path, "expected a vector object")
    known = {"name", "rules", "divergences", "summary", "fleet", "robot", "config", "state", "steps"}
    extra = set(data) - known
    if extra:
        raise InvalidVector(source, path, f"unknown keys {sorted(extra)}")
    name = _require(source, path, data, "name", str)
    rules = _require(source, path, data, "rules", list)
    if not rules or not all(isinstance(rule, str) for rule in rules):
        raise InvalidVector(source, f"{path}.rules", "expected a non-empty list of rule numbers")
    divergences = data.get("divergences", [])
    if not isinstance(divergences, list) or not all(isinstance(item, str) for item in divergences):
        raise InvalidVector(source, f"{path}.divergences", 'expected a list of divergence numbers ("D1"...)')
    steps_data = _require(source, path, data, "steps", list)
    steps = []
    for index, step in enumerate(steps_data):
        where = f"{path}.steps[{index}]"
        if not isinstance(step, dict) or set(step) - {"input", "expect", "view"}:
            raise InvalidVector(
                source, where, "expected an object with 'input', 'expect' and optional 'view'"
            )
        _require(source, where, step, "input", dict)
        expect = _require(source, where, step, "expect", list)
        steps.append(Step(input=step["input"], expect=tuple(expect), view=step.get("view")))
    state = data.get("state", "fresh")
    return Vector(
        name=name,
        rules=tuple(rules),
        divergences=tuple(divergences),
        summary=str(data.get("summary", "")),
        source=source,
        fleet=_require(source, path, data, "fleet", str),
        robot=_require(source, path, data, "robot", str),
        config=_require(source, path, data, "config", dict),
        state=None if state == "fresh" else state,
        steps=tuple(steps),
    )


def parse_vector_file(source: str, text: str | bytes, *, schema: bool = False) -> list[Vector]:
    """The vectors of one file's text; raises :class:`InvalidVector` naming ``source``.

    With ``schema``, the file is first validated against the shipped JSON Schema
    (``conformance/vector.schema.json``) by the ``jsonschema`` package, when it
    is installed (the ``vectors`` extra): a typo in an ``expect`` is then a
    vector-file error naming the vector and the path, not a failure of the
    implementation under test.
    """
    try:
        data = _json.parse(text)
    except _json.JsonProblem as exc:
        raise InvalidVector(source, "$", str(exc)) from None
    if schema:
        problem = schema_problem(data)
        if problem is not None:
            raise InvalidVector(source, *problem)
    vectors = _require(source, "$", data, "vectors", list)
    return [_vector(source, f"$.vectors[{index}]", item) for index, item in enumerate(vectors)]


def schema_validation_available() -> bool:
    """Whether :func:`schema_problem` can validate (the ``jsonschema`` package is installed)."""
    try:
        import jsonschema  # noqa: F401
    except ImportError:
        return False
    return True


def schema_problem(data: Any) -> tuple[str, str] | None:
    """The most relevant way ``data`` breaks the vector file schema, as (JSON path, problem).

    None when it conforms, or when ``jsonschema`` is not installed.  The path
    names the vector by its ``name`` where the file gives one.
    """
    try:
        import jsonschema
    except ImportError:
        return None
    schema = _json.parse((resources.files("dynevent") / "conformance" / SCHEMA_FILE).read_bytes())
    error = jsonschema.exceptions.best_match(jsonschema.Draft202012Validator(schema).iter_errors(data))
    if error is None:
        return None
    path = error.json_path
    where = list(error.absolute_path)
    if len(where) >= 2 and where[0] == "vectors" and isinstance(data, dict):
        try:
            name = data["vectors"][where[1]]["name"]
        except (KeyError, IndexError, TypeError):
            name = None
        if isinstance(name, str):
            path = f"{path} (vector {name!r})"
    message = error.message if len(error.message) <= 300 else error.message[:297] + "..."
    return path, f"{message} (the vector file schema)"


def load_vectors(paths: Iterable[str | os.PathLike[str]] = ()) -> list[Vector]:
    """The vectors of the given files, or the shipped ones when none are given.

    Given files are validated against the shipped JSON Schema first, where
    ``jsonschema`` is installed (see :func:`parse_vector_file`).
    """
    found: list[Vector] = []
    chosen = [os.fspath(path) for path in paths]
    if chosen:
        for path in chosen:
            try:
                with open(path, "rb") as handle:
                    text = handle.read()
            except OSError as exc:
                raise InvalidVector(path, "$", f"cannot read: {exc.strerror}") from None
            found.extend(parse_vector_file(path, text, schema=True))
    else:
        folder = resources.files("dynevent") / "conformance"
        for entry in sorted(folder.iterdir(), key=lambda item: item.name):
            if entry.name.endswith(".json") and not entry.name.endswith(".schema.json"):
                found.extend(parse_vector_file(f"conformance/{entry.name}", entry.read_bytes()))
    names = [vector.name for vector in found]
    duplicates = sorted({name for name in names if names.count(name) > 1})
    if duplicates:
        raise InvalidVector("vectors", "$", f"duplicate vector names {duplicates}")
    return found


# --------------------------------------------------------------------------- running


def matches(expected: Any, got: Any) -> bool:
    """Does ``got`` fit ``expected``?  Exact, but ``"*"`` matches any string."""
    if expected == WILDCARD and isinstance(got, str):
        return True
    if isinstance(expected, dict):
        return (
            isinstance(got, dict)
            and expected.keys() == got.keys()
            and all(matches(value, got[key]) for key, value in expected.items())
        )
    if isinstance(expected, list):
        return isinstance(got, list) and len(expected) == len(got) and all(map(matches, expected, got))
    if isinstance(expected, bool) or isinstance(got, bool):
        return expected is got
    return bool(expected == got)


@attrs.frozen
class Failure:
    """Where and how a vector failed."""

    step: int
    input: Any
    expected: Any
    got: Any
    problem: str

    def diff(self) -> str:
        """A readable account: the step, its input, then expected and got as a sequence diff.

        Outputs are aligned by the longest run of matching ones, so one extra or
        missing output marks that output alone: ``=`` both sides match, ``-``
        expected but not given, ``+`` given but not expected.
        """
        lines = [
            f"step {self.step}: {self.problem}",
            f"  input:    {_json.dumps(self.input)}",
            "  (= as expected, - expected but missing, + not expected)",
        ]
        expected = list(self.expected) if isinstance(self.expected, (list, tuple)) else [self.expected]
        got = list(self.got) if isinstance(self.got, (list, tuple)) else [self.got]
        for mark, value in align(expected, got):
            lines.append(f"  {mark} {_json.dumps(value)}")
        return "\n".join(lines)


def align(expected: Sequence[Any], got: Sequence[Any]) -> list[tuple[str, Any]]:
    """The two output lists as one sequence diff under :func:`matches`: ``("=", got)``,
    ``("-", expected)`` and ``("+", got)`` entries, along a longest common subsequence."""
    rows, cols = len(expected), len(got)
    best = [[0] * (cols + 1) for _ in range(rows + 1)]
    for i in range(rows - 1, -1, -1):
        for j in range(cols - 1, -1, -1):
            if matches(expected[i], got[j]):
                best[i][j] = best[i + 1][j + 1] + 1
            else:
                best[i][j] = max(best[i + 1][j], best[i][j + 1])
    entries: list[tuple[str, Any]] = []
    i = j = 0
    while i < rows or j < cols:
        if i < rows and j < cols and matches(expected[i], got[j]) and best[i][j] == best[i + 1][j + 1] + 1:
            entries.append(("=", got[j]))
            i, j = i + 1, j + 1
        elif i < rows and (j == cols or best[i + 1][j] >= best[i][j + 1]):
            entries.append(("-", expected[i]))
            i += 1
        else:
            entries.append(("+", got[j]))
            j += 1
    return entries


@attrs.frozen
class Outcome:
    """The result of one vector."""

    vector: Vector
    failure: Failure | None

    @property
    def passed(self) -> bool:
        """True when every step matched."""
        return self.failure is None


def run_vector(vector: Vector, implementation: Implementation) -> Outcome:
    """Run one vector; stop at the first mismatch."""
    try:
        implementation.reset(vector.fleet, vector.robot, vector.config, vector.state)
    except DyneventError as exc:
        return Outcome(vector, Failure(0, None, None, None, f"reset failed: {exc}"))
    for index, step in enumerate(vector.steps, start=1):
        try:
            outputs, view = implementation.apply(step.input)
        except DyneventError as exc:
            return Outcome(vector, Failure(index, step.input, list(step.expect), [], f"apply failed: {exc}"))
        if not matches(list(step.expect), outputs):
            return Outcome(vector, Failure(index, step.input, list(step.expect), outputs, "outputs differ"))
        if step.view is not None and not matches(step.view, view):
            return Outcome(vector, Failure(index, step.input, [step.view], [view], "view differs"))
    return Outcome(vector, None)


def run_vectors(vectors: Sequence[Vector], implementation: Implementation) -> Iterator[Outcome]:
    """Run every vector in turn."""
    for vector in vectors:
        yield run_vector(vector, implementation)


# --------------------------------------------------------------------------- reporting

_RULE = re.compile(r"R(\d+)\.(\d+)")


def _rule_key(rule: str) -> tuple[int, int, str]:
    found = _RULE.fullmatch(rule)
    return (int(found.group(1)), int(found.group(2)), "") if found else (10**9, 0, rule)


def select_vectors(vectors: Sequence[Vector], filters: Sequence[str] | None) -> list[Vector]:
    """The vectors any filter selects (all of them when there is no filter).

    A filter that is a rule number (``R9.3``) selects the vectors citing it; one
    with glob characters (``*?[``) is matched against the whole name; any
    other selects the vectors whose name contains it.
    """
    if not filters:
        return list(vectors)

    def chosen(vector: Vector, pattern: str) -> bool:
        if _RULE.fullmatch(pattern):
            return pattern in vector.rules
        if any(char in pattern for char in "*?["):
            return fnmatch.fnmatchcase(vector.name, pattern)
        return pattern in vector.name

    return [vector for vector in vectors if any(chosen(vector, pattern) for pattern in filters)]


@attrs.frozen
class RuleTally:
    """How the vectors citing one rule fared."""

    rule: str
    vectors: int
    passed: int

    @property
    def failed(self) -> int:
        """Vectors citing the rule that failed."""
        return self.vectors - self.passed


def rule_table(outcomes: Iterable[Outcome]) -> list[RuleTally]:
    """One tally per cited rule, in rule order."""
    counts: dict[str, list[int]] = {}
    for outcome in outcomes:
        for rule in dict.fromkeys(outcome.vector.rules):
            tally = counts.setdefault(rule, [0, 0])
            tally[0] += 1
            tally[1] += outcome.passed
    return [
        RuleTally(rule, total, passed)
        for rule, (total, passed) in sorted(counts.items(), key=lambda item: _rule_key(item[0]))
    ]


def format_report(outcomes: Sequence[Outcome], implementation: str = "") -> str:
    """The human report: the table by rule, a diff per failed vector, and ``N passed, M failed``."""
    lines = [f"implementation: {implementation}"] if implementation else []
    table = rule_table(outcomes)
    width = max([len("rule"), *(len(tally.rule) for tally in table)])
    lines.append(f"{'rule':<{width}}  {'vectors':>7}  {'passed':>6}  {'failed':>6}")
    for tally in table:
        mark = "" if tally.failed == 0 else "  FAIL"
        lines.append(f"{tally.rule:<{width}}  {tally.vectors:>7}  {tally.passed:>6}  {tally.failed:>6}{mark}")
    failed = [outcome for outcome in outcomes if outcome.failure is not None]
    for outcome in failed:
        vector = outcome.vector
        assert outcome.failure is not None
        lines.append("")
        lines.append(f"FAIL {vector.name} ({vector.source}) [{', '.join(vector.rules)}]")
        if vector.summary:
            lines.append(f"  {vector.summary}")
        lines.extend(f"  {line}" for line in outcome.failure.diff().splitlines())
    lines.append("")
    lines.append(f"{len(outcomes) - len(failed)} passed, {len(failed)} failed")
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
        "failure": None
        if failure is None
        else {
            "step": failure.step,
            "problem": failure.problem,
            "input": failure.input,
            "expected": failure.expected,
            "got": failure.got,
            "diff": failure.diff(),
        },
    }


def summary_record(outcomes: Sequence[Outcome], implementation: str = "") -> dict[str, Any]:
    """The closing JSON object of ``dynevent vectors --json``."""
    passed = sum(outcome.passed for outcome in outcomes)
    return {
        "type": "summary",
        "implementation": implementation,
        "vectors": len(outcomes),
        "passed": passed,
        "failed": len(outcomes) - passed,
        "rules": {
            tally.rule: {"vectors": tally.vectors, "passed": tally.passed, "failed": tally.failed}
            for tally in rule_table(outcomes)
        },
    }
