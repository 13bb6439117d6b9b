"""The field's event description schemas, and a description's shape judged by them.

The schemas (``dynevent/descriptions/schemas/*.json``, JSON Schema draft
2020-12) are the project's own text of the shapes the deployed fleet adapter
accepts for each category a dynamic event's child may use: ``go_to_place``,
``perform_action``, ``sequence``, ``clean``, ``pickup`` and ``dropoff``, with
``place.json`` and ``payload_transfer.json`` shared.  :func:`conforms` gives
the verdict (a compiled predicate, :mod:`dynevent.descriptions._compile`);
:func:`shape_errors` says why a description fails, one line per fault with its
JSON pointer, from the ``jsonschema`` package (the ``descriptions`` extra).
"""

from __future__ import annotations

import copy
import functools
import json
from collections.abc import Mapping
from importlib import resources
from typing import Any

from dynevent.descriptions import _compile, _explain
from dynevent.errors import MissingExtra, UnknownCategory
from dynevent.server.config import MAX_LISTED_ERRORS, listed_errors

__all__ = ["CATEGORIES", "conforms", "form", "require_explanations", "schema", "schemas", "shape_errors"]

#: The categories whose descriptions the schemas define, in the order the docs present them.
CATEGORIES: tuple[str, ...] = ("go_to_place", "perform_action", "sequence", "clean", "pickup", "dropoff")

#: Schemas other schemas refer to; not categories of their own.
_SHARED = ("place", "payload_transfer")


def schemas() -> dict[str, dict[str, Any]]:
    """Every schema by its ``$id`` (``"go_to_place.json"``, ``"place.json"``...), as parsed JSON: a
    copy of its own, which the caller may change (some validators rewrite the references they read)."""
    return {name: copy.deepcopy(dict(document)) for name, document in _schemas().items()}


@functools.cache
def _schemas() -> Mapping[str, Mapping[str, Any]]:
    folder = resources.files("dynevent.descriptions") / "schemas"
    loaded = {}
    for name in (*CATEGORIES, *_SHARED):
        document = json.loads((folder / f"{name}.json").read_text(encoding="utf-8"))
        loaded[document["$id"]] = document
    return loaded


def schema(category: str) -> dict[str, Any]:
    """The schema of ``category``'s descriptions (a copy of its own); raises
    :class:`~dynevent.errors.UnknownCategory`."""
    return copy.deepcopy(dict(_schemas()[_document(category)]))


def _document(category: object) -> str:
    return f"{_category(category)}.json"


def _category(category: object) -> str:
    """``category``, one of :data:`CATEGORIES`; anything else (of any type) is
    :class:`~dynevent.errors.UnknownCategory`, before a cache that would hash it."""
    if not isinstance(category, str) or category not in CATEGORIES:
        raise UnknownCategory(category, CATEGORIES)
    return category


@functools.cache
def _predicate(category: str) -> _compile.Predicate:
    return _compile.compile_schema(_document(category), _schemas())


@functools.cache
def _forms(category: str) -> tuple[_compile.Predicate, ...]:
    document = _document(category)
    count = len(_schemas()[document].get("oneOf", ()))
    return tuple(
        _compile.compile_schema(f"{document}#/oneOf/{number}", _schemas()) for number in range(count)
    )


def form(category: str, description: Any, *, conforming: bool = False) -> int | None:
    """Which form of ``category``'s schema a conforming description takes: the index of the one
    branch of its top-level ``oneOf`` that it fits (``go_to_place``: 0 a place, 1 ``{"place": ...}``,
    2 ``{"one_of": [...]}``), or ``None`` for a schema without forms or a description that does
    not conform.  Keys do not tell: ``{"place": "A", "one_of": 5}`` is of the second form.
    ``conforming=True`` says the caller has just seen it conform (it is not judged twice)."""
    if not conforming and not conforms(category, description):
        return None
    forms = _forms(_category(category))
    return next((number for number, fits in enumerate(forms) if fits(description)), None)


def conforms(category: str, description: Any) -> bool:
    """Whether ``description`` (parsed JSON) has a shape ``category``'s schema accepts."""
    return _predicate(_category(category))(description)


@functools.cache
def _validator(category: str) -> Any:
    """The ``jsonschema`` validator of ``category``, or ``None`` without the package.

    Its ``items`` lists the faults of the first few members at fault only, and skips a member
    the compiled schema accepts without asking the package (R4.19): an array of any length is
    explained in time linear in its length, with a small constant."""
    try:
        import jsonschema
        import referencing
    except ImportError:
        return None
    draft = referencing.jsonschema.DRAFT202012
    # without "$schema", a document that a $ref leads into keeps this class (the package picks a
    # document's class by its "$schema"), so that the bounded "items" holds everywhere
    documents = {
        name: {key: value for key, value in document.items() if key != "$schema"}
        for name, document in _schemas().items()
    }
    registry: Any = referencing.Registry().with_resources(
        (name, referencing.Resource.from_contents(document, default_specification=draft))
        for name, document in documents.items()
    )
    accepts = _compile.compile_subschemas("items", documents)

    def items(validator: Any, items: Any, instance: Any, schema: Any) -> Any:
        if not validator.is_type(instance, "array"):
            return
        known = accepts.get(id(items))
        fits = known[1] if known is not None and known[0] is items else None
        at_fault = 0
        for index, item in enumerate(instance):
            if fits is not None and fits(item):
                continue
            errors = list(validator.descend(instance=item, schema=items, path=index))
            if errors:
                yield from errors
                at_fault += 1
                if at_fault > MAX_LISTED_ERRORS:
                    return

    bounded = jsonschema.validators.extend(jsonschema.Draft202012Validator, {"items": items})
    return bounded(documents[_document(category)], registry=registry)


def require_explanations() -> None:
    """Raise :class:`~dynevent.errors.MissingExtra` unless the ``jsonschema`` package is there to say
    where a description goes wrong (what a server that client authors develop against must say)."""
    if _validator("go_to_place") is None:
        raise MissingExtra("descriptions", "jsonschema", "says where a refused description goes wrong")


def shape_errors(category: str, description: Any) -> tuple[str, ...]:
    """Why ``description`` fails ``category``'s schema, one line per fault (none when it conforms).

    Each line is ``<JSON pointer>: <fault>``, e.g. ``/one_of/1: 5.5 is not a place``; the
    description itself is ``/``.  At most :data:`~dynevent.server.config.MAX_LISTED_ERRORS` are
    listed (R4.19), found in time linear in the description's size.  The lines come from the
    ``jsonschema`` package (the ``descriptions`` extra); without it the verdict is the same and
    the one line says only that the description is not of the category, and how to learn where.
    """
    if conforms(category, description):
        return ()
    title = _schemas()[_document(category)].get("title", category)
    validator = _validator(category)
    if validator is None:
        hint = "pip install 'dynevent[descriptions]' to be told where"
        return (f"/: {_explain.render(description)} is not {title} ({hint})",)
    try:
        lines = _explain.explain(validator.iter_errors(description))
    except ValueError:  # the package wrote an integer too long to write into a message
        writable = _explain.writable(description)
        if writable is description:
            raise
        lines = _explain.explain(validator.iter_errors(writable))
    # The compiled verdict and the package agree on every instance (tests/descriptions); were
    # they ever to differ, the refusal still says so rather than refusing without a reason.
    return listed_errors(lines) or (f"/: {_explain.render(description)} is not {title}",)
