"""Vector files: the model of a vector, reading and checking the files, choosing vectors.

A vector is a scripted exchange written from docs/spec.md: a server
configuration, an initial state, and steps, each an input and the exact
outputs the spec requires in answer (and optionally the phase, seq and current
id after it).  The vectors ship with the package (``dynevent/conformance/vectors/``,
one JSON file per spec section, with the JSON Schema ``vector.schema.json``).
"""

from __future__ import annotations

import fnmatch
import os
import re
from collections.abc import Iterable, Sequence
from importlib import resources
from typing import Any

import attrs

from dynevent import files
from dynevent.errors import FileError, InvalidVector
from dynevent.wire import _json

__all__ = [
    "SCHEMA_FILE",
    "Step",
    "Vector",
    "load_vectors",
    "parse_vector_file",
    "rule_key",
    "schema_problem",
    "schema_validation_available",
    "select_vectors",
]

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
    (``conformance/vectors/vector.schema.json``) by the ``jsonschema`` package, when it
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
    schema = _json.parse((resources.files("dynevent") / "conformance" / "vectors" / SCHEMA_FILE).read_bytes())
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
                text = files.read_bytes(path, "vector file")
            except FileError as exc:
                raise InvalidVector(path, "$", exc.problem) from None
            found.extend(parse_vector_file(path, text, schema=True))
    else:
        folder = resources.files("dynevent") / "conformance" / "vectors"
        for entry in sorted(folder.iterdir(), key=lambda item: item.name):
            if entry.name.endswith(".json") and not entry.name.endswith(".schema.json"):
                found.extend(parse_vector_file(f"conformance/vectors/{entry.name}", entry.read_bytes()))
    names = [vector.name for vector in found]
    duplicates = sorted({name for name in names if names.count(name) > 1})
    if duplicates:
        raise InvalidVector("vectors", "$", f"duplicate vector names {duplicates}")
    return found


_RULE = re.compile(r"R(\d{1,9})\.(\d{1,9})")  # a rule number of ten digits is no rule of the spec


def rule_key(rule: str) -> tuple[int, int, str]:
    """A sort key putting rule numbers in spec order (R2.10 after R2.9), other names last."""
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
