"""The ``dynamic_event`` event description: the JSON a task carries for the event.

A task that contains a dynamic event carries this JSON object as the event's
description, and the robot publishes its full text on the begin topics.  It
has five known fields and may have any others::

    {
      "estimate":   {"category": "go_to_place", "description": {...}},
      "required":   [{"category": "perform_action", "description": {...}}],
      "category":   "patrol",           (header category; "dynamic_event" if absent)
      "detail":     "patrol the lobby", (header detail)
      "parameters": {...},              (free, for the dynamic event client)
      "custom":     ...                 (any other field, kept untouched)
    }

:class:`EventDescription` models the object and :class:`EventSpec` one event
of ``estimate`` or ``required``.

Decisions, where the schema ``event_description__dynamic_event.json`` is
silent or looser than the fleet adapter that reads it:

- An :class:`EventSpec` needs a string ``category``.  The schema does not mark
  it required, but the estimate builds the task model and each required event
  is looked up by category (``rmf_fleet_adapter`` reads both with
  ``at("category")``, which throws when it is missing).  ``description`` stays
  optional, as in the schema, although that adapter's ``at("description")``
  throws when it is absent too.
- The top-level ``category`` has no type in the schema; it overrides the
  event header's category, so it must be a string.
- ``null`` is not a value of any typed field: ``"detail": null`` is refused
  rather than read as absent, as the adapter's ``get<std::string>()`` does.
- Strings holding a lone UTF-16 surrogate (the JSON escape ``"\\ud800"``) are
  refused, since the text could not then be written as UTF-8 for the wire.
- Nesting is limited to :data:`dynevent.wire._json.MAX_DEPTH` levels counted from
  the top-level object, and text to :data:`MAX_DESCRIPTION_BYTES`, checked
  before parsing.

Round trip: every field is kept, unknown ones included (also inside
``estimate`` and ``required`` items), absent fields stay absent and present
ones stay present (``"required": []`` is not dropped, an absent ``category`` is
not written out as ``"dynamic_event"``), and the order of keys is kept, so
``EventDescription.from_json(text).to_json()`` is the compact form of ``text``.

Immutability: free JSON values (``description``, ``parameters``, unknown
fields) are held as :class:`JsonValue`, their compact JSON text, so every
class here is frozen and hashable.  Two values are equal exactly when they
write the same JSON text: key order matters, and ``1`` and ``1.0`` differ.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import attrs

from dynevent.errors import InvalidDescription, short_repr
from dynevent.wire._json import MAX_DEPTH, JsonProblem, dumps, parse, utf8_size

__all__ = [
    "DEFAULT_CATEGORY",
    "MAX_DESCRIPTION_BYTES",
    "EventDescription",
    "EventSpec",
    "JsonValue",
]

#: The header category of a dynamic event whose description has no ``category``.
DEFAULT_CATEGORY = "dynamic_event"

#: Largest description text accepted by :meth:`EventDescription.from_json`, in UTF-8 bytes.
MAX_DESCRIPTION_BYTES = 1_000_000

_SPEC_SHAPE = 'expected an object with "category" (string) and optional "description"'
_SPEC_FIELDS = ("category", "description")
_DESCRIPTION_FIELDS = ("estimate", "required", "category", "detail", "parameters")
_GOT_LIMIT = 40

#: Unknown fields, as ``(key, value)`` pairs in key order.
Extra = tuple[tuple[str, "JsonValue"], ...]


# ---------------------------------------------------------------------------
# Locating and naming what was refused


def _member(path: str, key: str) -> str:
    """Return the path of ``key`` inside the object at ``path``."""
    if key.isascii() and key.isidentifier():
        return f"{path}.{key}"
    return f"{path}[{dumps(key)}]"


def _got(value: object) -> str:
    """Name a refused value as a JSON reader sees it: its type or its text."""
    if isinstance(value, dict):
        return "object"
    if isinstance(value, (list, tuple)):
        return "array"
    if value is None or isinstance(value, (bool, int, float, str)):
        try:
            text = dumps(value)
        except ValueError:  # an int too long for str() since Python 3.11
            return "an integer too long to write"
        if len(text) > _GOT_LIMIT:
            text = f"{text[: _GOT_LIMIT - 3]}..."
        return text
    return f"a Python {type(value).__name__}"


# ---------------------------------------------------------------------------
# Free JSON values


def _check_text(text: str, path: str) -> None:
    """Refuse a string that UTF-8 cannot carry (a lone surrogate)."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise InvalidDescription(
            path,
            f"string holds a lone surrogate U+{ord(text[exc.start]):04X} at index {exc.start},"
            " which UTF-8 cannot carry",
        ) from None


def _check_keys(obj: Mapping[Any, Any], path: str) -> None:
    """Refuse object keys that are not strings, or that UTF-8 cannot carry."""
    for key in obj:
        if not isinstance(key, str):
            raise InvalidDescription(path, f"object key {short_repr(key)} is not a string")
        _check_text(key, path)


def _check_json(value: object, path: str, enclosing: int) -> int:
    """Refuse ``value`` unless it is a JSON value; return its nesting depth.

    ``enclosing`` counts the arrays and objects around ``value`` in the whole
    document, so that the document stays within ``MAX_DEPTH`` levels.
    """
    if value is None or isinstance(value, (bool, float)):
        return 0
    if isinstance(value, str):
        _check_text(value, path)
        return 0
    if isinstance(value, int):
        try:
            int.__repr__(value)
        except ValueError:  # Python 3.11+ will not write ints of more than 4300 digits
            raise InvalidDescription(path, "integer has too many digits to write") from None
        return 0
    if isinstance(value, (dict, list, tuple)):
        if enclosing + 1 > MAX_DEPTH:
            raise InvalidDescription(path, f"nested deeper than {MAX_DEPTH} levels")
        deepest = 0
        if isinstance(value, dict):
            _check_keys(value, path)
            for key, item in value.items():
                deepest = max(deepest, _check_json(item, _member(path, key), enclosing + 1))
        else:
            for index, item in enumerate(value):
                deepest = max(deepest, _check_json(item, f"{path}[{index}]", enclosing + 1))
        return deepest + 1
    raise InvalidDescription(path, f"expected a JSON value, got {_got(value)}")


@attrs.frozen
class JsonValue:
    """One free JSON value, held as its compact JSON text.

    Holding text keeps the value immutable and hashable; :attr:`value` returns
    a fresh parsed copy each time.  Build one from a Python value with
    :meth:`of`, or from JSON text with ``JsonValue(text)``, which parses and
    compacts it.  Equal values have equal text: key order counts, ``1`` and
    ``1.0`` differ.  Refusals raise :class:`~dynevent.errors.InvalidDescription`.
    """

    text: str
    _nesting: int = attrs.field(init=False, eq=False, repr=False)

    def __attrs_post_init__(self) -> None:
        if not isinstance(self.text, str):
            raise InvalidDescription("$", f"expected JSON text, got {_got(self.text)}")
        try:
            value = parse(self.text)
        except JsonProblem as exc:
            raise InvalidDescription("$", str(exc)) from None
        nesting = _check_json(value, "$", 0)
        object.__setattr__(self, "text", dumps(value))
        object.__setattr__(self, "_nesting", nesting)

    @classmethod
    def of(cls, value: object) -> JsonValue:
        """Return the JSON value of a Python ``dict``/``list``/``str``/number/``bool``/``None``.

        Tuples are taken as arrays.  Object keys must be strings.
        """
        if isinstance(value, JsonValue):
            return value
        return _json_value(value, "$", 0)

    @property
    def value(self) -> Any:
        """A fresh parsed copy of the value."""
        return parse(self.text)

    @property
    def nesting(self) -> int:
        """How many levels of arrays and objects the value has (0 for a scalar)."""
        return self._nesting


def _json_value(value: object, path: str, enclosing: int) -> JsonValue:
    """Check ``value`` at ``path`` and wrap it without parsing its text again."""
    if isinstance(value, JsonValue):
        if enclosing + value.nesting > MAX_DEPTH:
            raise InvalidDescription(path, f"nested deeper than {MAX_DEPTH} levels")
        return value
    nesting = _check_json(value, path, enclosing)
    wrapped = object.__new__(JsonValue)
    # the text is written from a value just checked, so __init__'s parse is not needed
    object.__setattr__(wrapped, "text", dumps(value))
    object.__setattr__(wrapped, "_nesting", nesting)
    return wrapped


def _optional_json(value: object) -> JsonValue | None:
    """Converter: ``None`` means absent; anything else becomes a :class:`JsonValue`."""
    return None if value is None else JsonValue.of(value)


def _to_extra(value: object) -> Extra:
    """Converter: unknown fields from a mapping or from ``(key, value)`` pairs."""
    if isinstance(value, Mapping):
        _check_keys(value, "$")
        pairs: Iterable[object] = value.items()
    elif isinstance(value, (list, tuple)):
        pairs = value
    else:
        raise InvalidDescription("$", f"expected the unknown fields as a mapping, got {_got(value)}")
    extra: list[tuple[str, JsonValue]] = []
    seen: set[str] = set()
    for pair in pairs:
        if not (isinstance(pair, tuple) and len(pair) == 2 and isinstance(pair[0], str)):
            raise InvalidDescription("$", f"unknown field {short_repr(pair)} is not a (str, value) pair")
        key, item = pair
        _check_text(key, "$")
        if key in seen:
            raise InvalidDescription("$", f"unknown field {key!r} is given twice")
        seen.add(key)
        extra.append((key, _json_value(item, _member("$", key), 1)))
    return tuple(extra)


def _to_key_order(value: object) -> tuple[str, ...]:
    """Converter: the order of keys, a sequence of strings."""
    if not (isinstance(value, (list, tuple)) and all(isinstance(key, str) for key in value)):
        raise InvalidDescription("$", f"expected the key order as strings, got {short_repr(value)}")
    return tuple(value)


def _check_extra(extra: Extra, known: tuple[str, ...], path: str) -> None:
    """Refuse an unknown field named like a known one."""
    for key, _ in extra:
        if key in known:
            raise InvalidDescription(_member(path, key), f"{key!r} is a known field, not an unknown one")


def _arrange(
    present: tuple[str, ...], extra: Extra, key_order: tuple[str, ...]
) -> tuple[Extra, tuple[str, ...]]:
    """Put ``extra`` in key order and reduce the key order to its normal form.

    The known fields come first in schema order unless ``key_order`` says
    otherwise; keys it does not list follow in that order.  The key order is
    kept only when it differs from that default, so equal text means equal
    fields.
    """
    if not key_order:
        return extra, ()
    keys = present + tuple(key for key, _ in extra)
    # sets, not tuples: a hostile text may hold a hundred thousand keys
    present_keys = set(keys)
    listed = {key: None for key in key_order if key in present_keys}
    order = tuple(listed) + tuple(key for key in keys if key not in listed)
    rank = {key: index for index, key in enumerate(order)}
    arranged = tuple(sorted(extra, key=lambda pair: rank[pair[0]]))
    default = present + tuple(key for key, _ in arranged)
    return arranged, (() if order == default else order)


def _object_text(order: tuple[str, ...], members: dict[str, str]) -> str:
    """Write a JSON object from member texts, in ``order`` (or theirs if empty)."""
    keys = order or tuple(members)
    return "{" + ",".join(f"{dumps(key)}:{members[key]}" for key in keys) + "}"


# ---------------------------------------------------------------------------
# One event: estimate or required item


@attrs.frozen
class EventSpec:
    """One event of ``estimate`` or ``required``: ``{"category": ..., "description": ...}``.

    ``category`` names the event (``"go_to_place"``) and is required;
    ``description`` is the event's own description, any JSON value, ``None``
    when absent; ``extra`` keeps any other fields, as ``(key, JsonValue)``
    pairs (a mapping is accepted); ``key_order`` is the order of keys in
    :meth:`to_json`, set by :meth:`from_dict`, empty for the default order.
    Refusals raise :class:`~dynevent.errors.InvalidDescription` located
    relative to this event (``$.category``).
    """

    category: str
    description: JsonValue | None = attrs.field(default=None, converter=_optional_json)
    extra: Extra = attrs.field(default=(), converter=_to_extra)
    _key_order: tuple[str, ...] = attrs.field(
        default=(), converter=_to_key_order, alias="key_order", repr=False
    )

    def __attrs_post_init__(self) -> None:
        if not isinstance(self.category, str):
            raise InvalidDescription("$.category", f"expected a string, got {_got(self.category)}")
        _check_text(self.category, "$.category")
        object.__setattr__(self, "category", str.__str__(self.category))
        _check_extra(self.extra, _SPEC_FIELDS, "$")
        if self.nesting > MAX_DEPTH:
            raise InvalidDescription("$", f"nested deeper than {MAX_DEPTH} levels")
        present = ("category",) + (("description",) if self.description is not None else ())
        extra, key_order = _arrange(present, self.extra, self._key_order)
        object.__setattr__(self, "extra", extra)
        object.__setattr__(self, "_key_order", key_order)

    @property
    def nesting(self) -> int:
        """How many levels of arrays and objects the event's JSON object has."""
        inner = [value.nesting for _, value in self.extra]
        if self.description is not None:
            inner.append(self.description.nesting)
        return 1 + max(inner, default=0)

    @classmethod
    def from_dict(cls, obj: object) -> EventSpec:
        """Read an event from a parsed JSON object (``dict``)."""
        return _spec_from(obj, "$", 0)

    def to_json(self) -> str:
        """Write the event as compact JSON text, keeping every field and the key order."""
        members = {"category": dumps(self.category)}
        if self.description is not None:
            members["description"] = self.description.text
        members.update((key, value.text) for key, value in self.extra)
        return _object_text(self._key_order, members)

    def to_dict(self) -> dict[str, Any]:
        """Return the event as a fresh JSON object (``dict``)."""
        result: dict[str, Any] = parse(self.to_json())
        return result


def _spec_from(obj: object, path: str, enclosing: int) -> EventSpec:
    """Read an event at ``path``, inside ``enclosing`` arrays and objects."""
    if not isinstance(obj, dict):
        raise InvalidDescription(path, f"{_SPEC_SHAPE}, got {_got(obj)}")
    _check_keys(obj, path)
    if "category" not in obj:
        raise InvalidDescription(path, f'{_SPEC_SHAPE}, got an object without "category"')
    category = obj["category"]
    if not isinstance(category, str):
        raise InvalidDescription(_member(path, "category"), f"expected a string, got {_got(category)}")
    _check_text(category, _member(path, "category"))
    description = None
    if "description" in obj:
        description = _json_value(obj["description"], _member(path, "description"), enclosing + 1)
    extra = tuple(
        (key, _json_value(value, _member(path, key), enclosing + 1))
        for key, value in obj.items()
        if key not in _SPEC_FIELDS
    )
    return EventSpec(category, description, extra, key_order=tuple(obj))


def _optional_text(value: object, path: str) -> str | None:
    """Check an optional string field; return it as a plain ``str``."""
    if value is None:
        return None
    if not isinstance(value, str):
        raise InvalidDescription(path, f"expected a string, got {_got(value)}")
    _check_text(value, path)
    # a str subclass (a str enum, say) may override __str__; keep the characters
    return str.__str__(value)


def _optional_spec(value: object) -> EventSpec | None:
    """Converter: ``None`` means absent; a ``dict`` is read as an event."""
    if value is None or isinstance(value, EventSpec):
        return value
    return _spec_from(value, "$.estimate", 1)


def _optional_specs(value: object) -> tuple[EventSpec, ...] | None:
    """Converter: ``None`` means absent; else a sequence of events or ``dict``s."""
    if value is None:
        return None
    if not isinstance(value, (list, tuple)):
        raise InvalidDescription("$.required", f"expected an array of events, got {_got(value)}")
    return tuple(
        item if isinstance(item, EventSpec) else _spec_from(item, f"$.required[{index}]", 2)
        for index, item in enumerate(value)
    )


# ---------------------------------------------------------------------------
# The description


@attrs.frozen
class EventDescription:
    """The ``dynamic_event`` event description (R1.5).

    Construct with the fields as keywords; ``None`` (the default) means the
    field is absent from the JSON object:

    - ``estimate``: the :class:`EventSpec` (or ``dict``) that models the event
      for the task planner;
    - ``required``: the events (or ``dict``s) the fleet must support; the
      :attr:`required` property gives ``()`` when absent;
    - ``category``: the header category; the :attr:`category` property gives
      :data:`DEFAULT_CATEGORY` when absent;
    - ``detail``: the header detail;
    - ``parameters``: any JSON value, for the dynamic event client;
    - ``extra``: every other field, as ``(key, JsonValue)`` pairs (a mapping
      is accepted);
    - ``key_order``: the order of keys in :meth:`to_json`, set by
      :meth:`from_dict`, empty for the default order.

    Refusals raise :class:`~dynevent.errors.InvalidDescription`.
    """

    estimate: EventSpec | None = attrs.field(default=None, converter=_optional_spec)
    _required: tuple[EventSpec, ...] | None = attrs.field(
        default=None, converter=_optional_specs, alias="required"
    )
    _category: str | None = attrs.field(default=None, alias="category")
    detail: str | None = None
    parameters: JsonValue | None = attrs.field(default=None, converter=_optional_json)
    extra: Extra = attrs.field(default=(), converter=_to_extra)
    _key_order: tuple[str, ...] = attrs.field(
        default=(), converter=_to_key_order, alias="key_order", repr=False
    )

    def __attrs_post_init__(self) -> None:
        object.__setattr__(self, "_category", _optional_text(self._category, "$.category"))
        object.__setattr__(self, "detail", _optional_text(self.detail, "$.detail"))
        _check_extra(self.extra, _DESCRIPTION_FIELDS, "$")
        self._check_nesting()
        present = tuple(
            name
            for name, value in zip(
                _DESCRIPTION_FIELDS,
                (self.estimate, self._required, self._category, self.detail, self.parameters),
                strict=True,
            )
            if value is not None
        )
        extra, key_order = _arrange(present, self.extra, self._key_order)
        object.__setattr__(self, "extra", extra)
        object.__setattr__(self, "_key_order", key_order)

    def _check_nesting(self) -> None:
        """Refuse a member that would nest the object deeper than ``MAX_DEPTH``."""
        members: list[tuple[str, int]] = []
        if self.estimate is not None:
            members.append(("$.estimate", self.estimate.nesting))
        for index, spec in enumerate(self.required):
            members.append((f"$.required[{index}]", 1 + spec.nesting))
        if self.parameters is not None:
            members.append(("$.parameters", self.parameters.nesting))
        members.extend((_member("$", key), value.nesting) for key, value in self.extra)
        for path, nesting in members:
            if 1 + nesting > MAX_DEPTH:
                raise InvalidDescription(path, f"nested deeper than {MAX_DEPTH} levels")

    @property
    def required(self) -> tuple[EventSpec, ...]:
        """The events the fleet must support; ``()`` when the field is absent."""
        return self._required if self._required is not None else ()

    @property
    def category(self) -> str:
        """The header category: the ``category`` field, else :data:`DEFAULT_CATEGORY`."""
        return self._category if self._category is not None else DEFAULT_CATEGORY

    @classmethod
    def from_json(cls, text: str | bytes | bytearray) -> EventDescription:
        """Read a description from JSON text (``str``, or ``bytes``/``bytearray`` of UTF-8).

        The size is checked before parsing; invalid JSON is reported at ``$``.
        """
        if isinstance(text, str):
            # surrogatepass: a lone surrogate is refused after parsing, with its location
            size = utf8_size(text)
        elif isinstance(text, (bytes, bytearray)):
            size = len(text)
        else:
            raise InvalidDescription("$", f"expected JSON text (str or bytes), got {_got(text)}")
        if size > MAX_DESCRIPTION_BYTES:
            raise InvalidDescription(
                "$", f"description is {size} bytes, above the limit of {MAX_DESCRIPTION_BYTES}"
            )
        try:
            obj = parse(text)
        except JsonProblem as exc:
            raise InvalidDescription("$", str(exc)) from None
        return cls.from_dict(obj)

    @classmethod
    def from_dict(cls, obj: object) -> EventDescription:
        """Read a description from a parsed JSON object (``dict``).

        No size limit applies here; nesting is limited as for text.
        """
        if not isinstance(obj, dict):
            raise InvalidDescription("$", f"expected a JSON object, got {_got(obj)}")
        _check_keys(obj, "$")
        estimate = _spec_from(obj["estimate"], "$.estimate", 1) if "estimate" in obj else None
        required = None
        if "required" in obj:
            items = obj["required"]
            if not isinstance(items, (list, tuple)):
                raise InvalidDescription("$.required", f"expected an array of events, got {_got(items)}")
            required = tuple(_spec_from(item, f"$.required[{index}]", 2) for index, item in enumerate(items))
        texts: dict[str, str | None] = {}
        for field in ("category", "detail"):
            value = obj.get(field)
            if field in obj and not isinstance(value, str):
                raise InvalidDescription(f"$.{field}", f"expected a string, got {_got(value)}")
            texts[field] = value
        parameters = None
        if "parameters" in obj:
            parameters = _json_value(obj["parameters"], "$.parameters", 1)
        extra = tuple(
            (key, _json_value(value, _member("$", key), 1))
            for key, value in obj.items()
            if key not in _DESCRIPTION_FIELDS
        )
        return cls(
            estimate=estimate,
            required=required,
            category=texts["category"],
            detail=texts["detail"],
            parameters=parameters,
            extra=extra,
            key_order=tuple(obj),
        )

    def to_json(self) -> str:
        """Write the description as compact JSON text, keeping every field and the key order."""
        members: dict[str, str] = {}
        if self.estimate is not None:
            members["estimate"] = self.estimate.to_json()
        if self._required is not None:
            members["required"] = "[" + ",".join(spec.to_json() for spec in self._required) + "]"
        if self._category is not None:
            members["category"] = dumps(self._category)
        if self.detail is not None:
            members["detail"] = dumps(self.detail)
        if self.parameters is not None:
            members["parameters"] = self.parameters.text
        members.update((key, value.text) for key, value in self.extra)
        return _object_text(self._key_order, members)

    def to_dict(self) -> dict[str, Any]:
        """Return the description as a fresh JSON object (``dict``)."""
        result: dict[str, Any] = parse(self.to_json())
        return result
