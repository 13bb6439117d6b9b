"""A robot server's configuration (:class:`ServerConfig`): what the machine is run under, never state.

Each number is checked to the bounds the machine runs without overflow (R0.1), and a bad value
raises :class:`~dynevent.errors.InvalidConfig` naming the field.  The machine
(:mod:`dynevent.server.machine`) re-exports every name here.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, TypeAlias

import attrs

from dynevent.errors import InvalidConfig
from dynevent.wire.description import DEFAULT_CATEGORY, MAX_DESCRIPTION_BYTES
from dynevent.wire.vocab import Compatibility, IdPolicy

__all__ = [
    "MAX_LISTED_ERRORS",
    "METRES_RANGE",
    "MORE_ERRORS",
    "SECONDS_RANGE",
    "ServerConfig",
    "Validator",
    "any_description",
    "listed_errors",
]

#: A description validator: ``(category, parsed description) -> list of errors`` (empty when valid);
#: an iterable the machine reads lazily (R4.19: no more than one error past the listed ones).
Validator: TypeAlias = Callable[[str, Any], Iterable[str]]


#: The most errors a refusal of R4.10 lists (R4.19): a validator's further errors are not read.
MAX_LISTED_ERRORS = 8
#: The line that stands, as the last of a refusal's errors, for the errors not listed (R4.19).
MORE_ERRORS = f"(further errors not listed: a refusal lists the first {MAX_LISTED_ERRORS})"


def listed_errors(errors: Iterable[Any]) -> tuple[str, ...]:
    """The errors a refusal lists (R4.19): the first :data:`MAX_LISTED_ERRORS` of ``errors``, as
    text, and :data:`MORE_ERRORS` when there were more.  No error past the one after the last
    listed is read, so a validator that yields its errors lazily stops being asked there."""
    first = [str(error) for error in itertools.islice(errors, MAX_LISTED_ERRORS + 1)]
    if len(first) > MAX_LISTED_ERRORS:
        return (*first[:MAX_LISTED_ERRORS], MORE_ERRORS)
    return tuple(first)


def any_description(category: str, description: Any) -> Sequence[str]:
    """A category's validator that takes every description (its JSON is still checked, R4.9)."""
    return ()


def _categories(value: Mapping[str, Validator]) -> Mapping[str, Validator]:
    if not isinstance(value, Mapping):
        raise InvalidConfig("categories", value, "expected a mapping of category to validator")
    for name, validator in value.items():
        if not isinstance(name, str) or not callable(validator):
            raise InvalidConfig("categories", {name: validator}, "each category must map a str to a callable")
        if name == DEFAULT_CATEGORY:  # R4.17: a nested run would take the robot's only slot
            raise InvalidConfig(
                "categories",
                name,
                f"{DEFAULT_CATEGORY!r} can never be a child category: a nested run would break the outer one",
            )
    return dict(value)


def _id_policy(value: Any) -> IdPolicy:
    try:
        return IdPolicy(value)
    except ValueError:
        raise InvalidConfig(
            "id_policy", value, f"expected one of {[item.value for item in IdPolicy]}"
        ) from None


def _compatibility(value: Any) -> Compatibility:
    try:
        return Compatibility(value)
    except ValueError:
        choices = [item.value for item in Compatibility]
        raise InvalidConfig("compatibility", value, f"expected one of {choices}") from None


#: The bounds of the configuration's numbers (R0.1): what the machine can run without overflow.
SECONDS_RANGE = (0.001, 86_400.0)
METRES_RANGE = (0.01, 1_000_000.0)


def _within(bounds: tuple[float, float], unit: str) -> Callable[[Any, attrs.Attribute[Any], Any], None]:
    low, high = bounds

    def check(instance: Any, attribute: attrs.Attribute[Any], value: Any) -> None:
        # comparisons, not float(): an integer of any size is judged exactly, and NaN fails both
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:
            problem = f"expected a number of {unit} from {low:g} to {high:g}"
            raise InvalidConfig(attribute.name, value, problem)

    return check


def _description_limit(instance: Any, attribute: attrs.Attribute[Any], value: Any) -> None:
    if type(value) is not int or not 0 < value <= MAX_DESCRIPTION_BYTES:
        raise InvalidConfig(
            attribute.name, value, f"expected a positive integer of at most {MAX_DESCRIPTION_BYTES} (bytes)"
        )


def _seconds_value(value: Any) -> Any:
    if isinstance(value, (int, float)) and not isinstance(value, bool) and 0 < value <= SECONDS_RANGE[1]:
        return float(value)
    return value  # the validator names the fault


def _at_least_a_centimetre(value: Any) -> Any:
    if isinstance(value, (int, float)) and not isinstance(value, bool) and 0 < value <= METRES_RANGE[1]:
        return max(float(value), METRES_RANGE[0])
    return value  # the validator names the fault


@attrs.frozen(kw_only=True, eq=False)
class ServerConfig:
    """What a robot's server is configured with; not state, never snapshotted.

    ``categories`` maps each supported event category to its description
    validator; ``dynamic_event`` is refused (R4.17).  ``stubborn_move_threshold``
    is never below 0.01 m (a smaller value is raised to it, as rmf_ros2 does).
    ``max_description_length`` is in UTF-8 bytes, as the begin description's
    limit is, and never above it (R4.8).  A bad value raises
    :class:`~dynevent.errors.InvalidConfig` naming the field.
    """

    categories: Mapping[str, Validator] = attrs.field(factory=dict, converter=_categories)
    id_policy: IdPolicy = attrs.field(default=IdPolicy.GOAL, converter=_id_policy)
    compatibility: Compatibility = attrs.field(default=Compatibility.STANDARD, converter=_compatibility)
    stubborn_minimum: float = attrs.field(
        default=2.0, validator=_within(SECONDS_RANGE, "seconds"), converter=_seconds_value
    )
    stubborn_refresh: float = attrs.field(
        default=1.0, validator=_within(SECONDS_RANGE, "seconds"), converter=_seconds_value
    )
    stubborn_move_threshold: float = attrs.field(
        default=0.1,
        validator=_within(METRES_RANGE, "metres"),
        converter=_at_least_a_centimetre,
    )
    max_description_length: int = attrs.field(default=MAX_DESCRIPTION_BYTES, validator=_description_limit)

    @classmethod
    def rmf_ros2(cls, categories: Mapping[str, Validator]) -> ServerConfig:
        """The configuration that behaves as rmf_ros2 does where dynevent diverges by option: the
        ``rmf_ros2`` mode and the ``adapter`` id policy (R17.3)."""
        return cls(categories=categories, id_policy=IdPolicy.ADAPTER, compatibility=Compatibility.RMF_ROS2)
