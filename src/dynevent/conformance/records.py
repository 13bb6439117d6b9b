"""Inputs, outputs and server configurations as JSON records.

The conformance vectors, the driver protocol, ``dynevent demo --json`` and
traces all speak these forms, so another implementation needs only this page
(and docs/conformance.md) to read and write them:

- an input is an object with ``"type"`` (the input's kind, e.g.
  ``"goal_requested"``) and its fields: ``{"type": "tick", "now": 5000000000,
  "map_name": "L1", "x": 0.0, "y": 0.0}``; a goal is a ``Goal`` dict (ROS field
  names), a goal UUID 32 lowercase hexadecimal digits, times integer
  nanoseconds;
- an output likewise: ``{"type": "goal_rejected", "goal_uuid": "...",
  "rejection": {"reason": "seq_mismatch", ...}}``, messages as ROS dicts,
  enums as their string values;
- a configuration is an object whose ``categories`` map each supported
  category to a *description rule* (below), with optional ``id_policy``,
  ``compatibility``, ``stubborn_minimum``, ``stubborn_refresh``,
  ``stubborn_move_threshold`` and ``max_description_length``.

A description rule is a small, language-neutral validator: ``{"accept":
"any"}``, ``{"accept": "string"}``, ``{"accept": "number"}``, ``{"accept":
"array"}`` or ``{"accept": "object", "required": ["place", ...]}``, or a list
of rules of which one must fit (``[{"accept": "string"}, {"accept": "object",
"required": ["place"]}]``).  Its errors are sentences; their wording is not
normative.  ``{"accept": "field"}``, for a category of
:mod:`dynevent.descriptions`, is the field's check of R4.18 (the category's
schema, then the robot), with optional ``places`` (the map: waypoint names
by index, ``null`` for an unnamed one) and ``actions``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from dynevent import descriptions
from dynevent.errors import (
    InvalidConfig,
    InvalidRecord,  # defined there with every error; importable here too
    short_repr,
)
from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig, Validator
from dynevent.wire._codec import CodecError, decode, encode

__all__ = [
    "InvalidRecord",
    "config_from_json",
    "input_from_json",
    "input_to_json",
    "output_from_json",
    "output_to_json",
    "rule_validator",
]


def _typed(kind: str, value: Any) -> dict[str, Any]:
    record: dict[str, Any] = {"type": kind}
    record.update(encode(value))
    return record


def input_to_json(event: ins.Input) -> dict[str, Any]:
    """The JSON record of an input."""
    return _typed(event.KIND, event)


def output_to_json(output: outs.Output) -> dict[str, Any]:
    """The JSON record of an output."""
    return _typed(output.KIND, output)


def _from_json(kinds: Mapping[str, type[Any]], what: str, data: object, path: str) -> Any:
    if not isinstance(data, dict):
        raise InvalidRecord(path, f"expected an {what} object, got {type(data).__name__}")
    kind = data.get("type")
    cls = kinds.get(kind) if isinstance(kind, str) else None
    if cls is None:
        expected = f"expected one of the {what} types {sorted(kinds)}"
        raise InvalidRecord(f"{path}.type", f"{expected}, got {short_repr(kind)}")
    fields = {key: value for key, value in data.items() if key != "type"}
    try:
        return decode(cls, fields, path)
    except CodecError as exc:
        raise InvalidRecord(exc.path, exc.problem) from None


def input_from_json(data: object, path: str = "$") -> ins.Input:
    """The input a JSON record describes; raises :class:`InvalidRecord`."""
    result: ins.Input = _from_json(ins.INPUT_TYPES, "input", data, path)
    return result


def output_from_json(data: object, path: str = "$") -> outs.Output:
    """The output a JSON record describes; raises :class:`InvalidRecord`."""
    result: outs.Output = _from_json(outs.OUTPUT_TYPES, "output", data, path)
    return result


_JSON_TYPES: Mapping[str, tuple[type, ...]] = {
    "string": (str,),
    "number": (int, float),
    "array": (list,),
    "object": (dict,),
}


_FIELD_KEYS = {"accept", "places", "actions"}


def _check_field_rule(rule: dict[str, Any], path: str) -> None:
    extra = set(rule) - _FIELD_KEYS
    if extra:
        raise InvalidRecord(path, f"unknown keys {sorted(extra)}")
    for key in ("places", "actions"):
        if key in rule and not isinstance(rule[key], list):
            raise InvalidRecord(f"{path}.{key}", "expected a list")


def _check_rule(rule: object, path: str) -> None:
    if isinstance(rule, dict) and rule.get("accept") == "field":
        name = path.rsplit(".", maxsplit=1)[-1]
        if name not in descriptions.CATEGORIES:
            raise InvalidRecord(path, f"a field rule is for the categories {list(descriptions.CATEGORIES)}")
        _check_field_rule(rule, path)
        return
    if isinstance(rule, list):
        if not rule:
            raise InvalidRecord(path, "a list of description rules must not be empty")
        for index, option in enumerate(rule):
            _check_rule(option, f"{path}[{index}]")
        return
    if not isinstance(rule, dict):
        raise InvalidRecord(path, "expected a description rule object or a list of them")
    accept = rule.get("accept")
    if not isinstance(accept, str) or (accept != "any" and accept not in _JSON_TYPES):
        expected = f"expected one of {['any', *_JSON_TYPES]}"
        raise InvalidRecord(f"{path}.accept", f"{expected}, got {short_repr(accept)}")
    required = rule.get("required", [])
    if not isinstance(required, list) or not all(isinstance(key, str) for key in required):
        raise InvalidRecord(f"{path}.required", "expected a list of strings")
    if required and accept != "object":
        raise InvalidRecord(f"{path}.required", "only an object rule can require keys")
    extra = set(rule) - {"accept", "required"}
    if extra:
        raise InvalidRecord(path, f"unknown keys {sorted(extra)}")


def _rule_errors(rule: Any, description: Any) -> list[str]:
    if isinstance(rule, list):
        options = [_rule_errors(option, description) for option in rule]
        if any(not errors for errors in options):
            return []
        return ["fits none of the accepted forms: " + " / ".join("; ".join(errors) for errors in options)]
    accept = rule["accept"]
    if accept == "any":
        return []
    expected = _JSON_TYPES[accept]
    if isinstance(description, bool) or not isinstance(description, expected):
        return [f"expected {'an' if accept[0] in 'aeiou' else 'a'} {accept}"]
    present: Any = description  # an object here: only object rules require keys
    return [f"missing required key {key!r}" for key in rule.get("required", []) if key not in present]


def rule_validator(rule: object, path: str = "$") -> Validator:
    """A validator built from a description rule (see the module docs)."""
    _check_rule(rule, path)

    def validate(category: str, description: Any) -> Sequence[str]:
        return _rule_errors(rule, description)

    return validate


def _is_field(rule: object) -> bool:
    return isinstance(rule, dict) and rule.get("accept") == "field"


def _validators(categories: dict[str, Any], path: str) -> dict[str, Validator]:
    """Each category's validator: its rule's, or for a field rule the robot's (whose sequences may
    use every category of the configuration)."""
    plain = {
        name: rule_validator(rule, f"{path}.{name}")
        for name, rule in categories.items()
        if not _is_field(rule)
    }
    field = [name for name, rule in categories.items() if _is_field(rule)]
    validators = dict(plain)
    for name in field:
        rule = categories[name]
        _check_rule(rule, f"{path}.{name}")
        try:
            robot = descriptions.Robot(
                places=rule.get("places"), actions=rule.get("actions"), categories=field
            )
        except InvalidConfig as exc:
            raise InvalidRecord(f"{path}.{name}", str(exc)) from None
        validators[name] = robot.validators(plain)[name]
    return validators


def config_from_json(data: object, path: str = "$") -> ServerConfig:
    """A :class:`~dynevent.server.machine.ServerConfig` from its JSON form."""
    if not isinstance(data, dict):
        raise InvalidRecord(path, "expected a configuration object")
    allowed = {
        "categories",
        "id_policy",
        "compatibility",
        "stubborn_minimum",
        "stubborn_refresh",
        "stubborn_move_threshold",
        "max_description_length",
    }
    extra = set(data) - allowed
    if extra:
        raise InvalidRecord(path, f"unknown keys {sorted(extra)}")
    categories = data.get("categories", {})
    if not isinstance(categories, dict):
        raise InvalidRecord(f"{path}.categories", "expected an object of category -> description rule")
    values: dict[str, Any] = {"categories": _validators(categories, f"{path}.categories")}
    values.update({key: value for key, value in data.items() if key != "categories"})
    try:
        return ServerConfig(**values)
    except (ValueError, TypeError) as exc:
        raise InvalidRecord(path, str(exc)) from None
