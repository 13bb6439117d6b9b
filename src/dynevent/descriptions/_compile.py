"""JSON Schema (draft 2020-12) compiled to Python predicates: the verdict of a description check.

A schema becomes a tree of closures that answer ``valid or not`` and nothing
else, in about a microsecond for an everyday description (docs/performance.md).
Why errors are left to the ``jsonschema`` package: a verdict is needed on every
NEXT, an explanation only for the ones refused, and the package is the
authority on wording and paths.  The two must agree on every instance; the
test suite checks that they do, against the ``jsonschema`` package on the
field's own schema text (tests/descriptions).

Only the keywords the description schemas use are compiled, each with the
package's semantics (a float with no fraction is an integer, ``True`` is not a
number, ``minimum`` ignores non-numbers, NaN passes a ``minimum`` because it is
not less than it).  Any other keyword is refused when the schema is compiled,
so a schema this module cannot judge exactly is never judged at all.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from dynevent.errors import InvalidConfig

__all__ = ["Predicate", "compile_schema", "compile_subschemas"]

#: A compiled schema: ``predicate(instance) -> valid``.
Predicate = Callable[[Any], bool]

#: Keywords that annotate and never change a verdict.
_ANNOTATIONS = frozenset({"$schema", "$id", "$comment", "title", "description", "default", "examples"})


def _is_integer(value: Any) -> bool:
    if isinstance(value, bool):
        return False
    return isinstance(value, int) or (isinstance(value, float) and value.is_integer())


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


_TYPES: Mapping[str, Predicate] = {
    "object": lambda value: isinstance(value, dict),
    "array": lambda value: isinstance(value, list),
    "string": lambda value: isinstance(value, str),
    "integer": _is_integer,
    "number": _is_number,
    "boolean": lambda value: isinstance(value, bool),
    "null": lambda value: value is None,
}


class _Compiler:
    """Compiles the schemas of one registry (``$id`` to schema), each subschema once."""

    def __init__(self, registry: Mapping[str, Mapping[str, Any]]) -> None:
        self._registry = registry
        self._done: dict[tuple[str, str], Predicate] = {}

    def reference(self, base: str, ref: str) -> Predicate:
        """The predicate of ``ref`` read from the document ``base``, compiled on first use (so that
        a cycle of references compiles)."""
        document, _, pointer = ref.partition("#")
        document = document or base
        key = (document, pointer)
        if key not in self._done:
            compiled: list[Predicate] = []

            def later(value: Any) -> bool:  # stands in while a cycle of references compiles
                return compiled[0](value)

            self._done[key] = later
            compiled.append(self.schema(document, self._resolve(document, pointer)))
            self._done[key] = compiled[0]
        return self._done[key]

    def _resolve(self, document: str, pointer: str) -> Any:
        if document not in self._registry:
            raise InvalidConfig(
                "schema", document, "a $ref names a schema that is not in the registry", owner="descriptions"
            )
        node: Any = self._registry[document]
        for escaped in filter(None, pointer.split("/")):
            part = escaped.replace("~1", "/").replace("~0", "~")
            if isinstance(node, list) and part.isdigit() and int(part) < len(node):
                node = node[int(part)]
            elif isinstance(node, dict) and part in node:
                node = node[part]
            else:
                raise InvalidConfig(
                    "schema", f"{document}#{pointer}", "a $ref points at nothing", owner="descriptions"
                )
        return node

    def schema(self, base: str, schema: Any) -> Predicate:
        """The predicate of one (sub)schema of document ``base``."""
        if schema is True:
            return lambda value: True
        if schema is False:
            return lambda value: False
        if not isinstance(schema, dict):
            raise InvalidConfig(
                "schema", schema, "expected a schema (an object or a boolean)", owner="descriptions"
            )
        unknown = set(schema) - _ANNOTATIONS - set(_KEYWORDS) - {"$defs"}
        if unknown:
            raise InvalidConfig(
                "schema",
                sorted(unknown),
                f"keywords {base} uses and this compiler has not",
                owner="descriptions",
            )
        checks = [
            _KEYWORDS[keyword](self, base, schema[keyword], schema)
            for keyword in _KEYWORDS
            if keyword in schema
        ]
        if not checks:
            return lambda value: True
        if len(checks) == 1:
            return checks[0]
        return lambda value: all(check(value) for check in checks)


def _type(compiler: _Compiler, base: str, names: Any, schema: Mapping[str, Any]) -> Predicate:
    listed = [names] if isinstance(names, str) else list(names)
    unknown = [name for name in listed if name not in _TYPES]
    if unknown:
        raise InvalidConfig(
            "schema", unknown, f"types {base} uses that JSON Schema has not", owner="descriptions"
        )
    if len(listed) == 1:
        return _TYPES[listed[0]]
    predicates = tuple(_TYPES[name] for name in listed)
    return lambda value: any(predicate(value) for predicate in predicates)


def _required(compiler: _Compiler, base: str, names: Any, schema: Mapping[str, Any]) -> Predicate:
    keys = tuple(names)
    return lambda value: not isinstance(value, dict) or all(key in value for key in keys)


def _properties(compiler: _Compiler, base: str, properties: Any, schema: Mapping[str, Any]) -> Predicate:
    checks = tuple((name, compiler.schema(base, sub)) for name, sub in properties.items())

    def check(value: Any) -> bool:
        if not isinstance(value, dict):
            return True
        for name, predicate in checks:  # noqa: SIM110 - a loop, not all(): a third faster here
            if name in value and not predicate(value[name]):
                return False
        return True

    return check


def _items(compiler: _Compiler, base: str, items: Any, schema: Mapping[str, Any]) -> Predicate:
    predicate = compiler.schema(base, items)
    return lambda value: not isinstance(value, list) or all(predicate(item) for item in value)


def _min_items(compiler: _Compiler, base: str, count: Any, schema: Mapping[str, Any]) -> Predicate:
    return lambda value: not isinstance(value, list) or len(value) >= count


def _minimum(compiler: _Compiler, base: str, bound: Any, schema: Mapping[str, Any]) -> Predicate:
    return lambda value: not _is_number(value) or not value < bound


def _one_of(compiler: _Compiler, base: str, branches: Any, schema: Mapping[str, Any]) -> Predicate:
    predicates = tuple(compiler.schema(base, branch) for branch in branches)

    def check(value: Any) -> bool:
        matched = False
        for predicate in predicates:
            if predicate(value):
                if matched:
                    return False
                matched = True
        return matched

    return check


def _any_of(compiler: _Compiler, base: str, branches: Any, schema: Mapping[str, Any]) -> Predicate:
    predicates = tuple(compiler.schema(base, branch) for branch in branches)
    return lambda value: any(predicate(value) for predicate in predicates)


def _all_of(compiler: _Compiler, base: str, branches: Any, schema: Mapping[str, Any]) -> Predicate:
    predicates = tuple(compiler.schema(base, branch) for branch in branches)
    return lambda value: all(predicate(value) for predicate in predicates)


def _ref(compiler: _Compiler, base: str, ref: Any, schema: Mapping[str, Any]) -> Predicate:
    return compiler.reference(base, ref)


_Keyword = Callable[[_Compiler, str, Any, Mapping[str, Any]], Predicate]

#: The compiled keywords, in the order their checks run (the cheapest first).
_KEYWORDS: Mapping[str, _Keyword] = {
    "type": _type,
    "required": _required,
    "minItems": _min_items,
    "minimum": _minimum,
    "$ref": _ref,
    "properties": _properties,
    "items": _items,
    "allOf": _all_of,
    "anyOf": _any_of,
    "oneOf": _one_of,
}


def compile_schema(name: str, registry: Mapping[str, Mapping[str, Any]]) -> Predicate:
    """The predicate of the schema whose ``$id`` is ``name`` (or of a part of it:
    ``"go_to_place.json#/oneOf/1"``), its references read from ``registry`` (``$id`` to schema);
    raises :class:`~dynevent.errors.InvalidConfig` for a keyword it cannot judge."""
    document, _, pointer = name.partition("#")
    return _Compiler(registry).reference(document, "#" + pointer)


def compile_subschemas(
    keyword: str, registry: Mapping[str, Mapping[str, Any]]
) -> dict[int, tuple[Mapping[str, Any], Predicate]]:
    """The predicate of every subschema that is the value of ``keyword`` (``"items"``) anywhere in
    ``registry``'s documents, by the identity of that subschema (kept beside it, so that the
    identity stays its own): how an explanation skips the members a subschema accepts."""
    compiler = _Compiler(registry)
    found: dict[int, tuple[Mapping[str, Any], Predicate]] = {}
    for name, document in registry.items():
        pending: list[Any] = [document]
        while pending:
            node = pending.pop()
            if isinstance(node, list):
                pending.extend(node)
            elif isinstance(node, dict):
                sub = node.get(keyword)
                if isinstance(sub, dict):
                    found[id(sub)] = (sub, compiler.schema(name, sub))
                pending.extend(node.values())
    return found
