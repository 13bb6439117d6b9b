"""A description that fits its schema, read into typed values: what the child is asked to do.

:func:`read` takes a category and a parsed description that
:func:`~dynevent.descriptions.shapes.conforms` to its schema and returns a
:class:`GoToPlace`, :class:`PerformAction`, :class:`Sequence`, :class:`Clean`
or :class:`PayloadTransfer`.  It is what a fleet adapter's child (or
``dynevent serve``'s simulated one) starts from; the robot's own check
(:class:`~dynevent.descriptions.Robot`) reads descriptions the same way.
"""

from __future__ import annotations

import math
from typing import Any

import attrs

from dynevent.descriptions import shapes
from dynevent.errors import InvalidEventDescription, integer_text

__all__ = [
    "Activity",
    "Clean",
    "GoToPlace",
    "PayloadItem",
    "PayloadTransfer",
    "PerformAction",
    "Place",
    "Reading",
    "Sequence",
    "read",
]


@attrs.frozen
class Place:
    """A waypoint (a name, or an index from 0), and the orientation to end in (radians), if given."""

    waypoint: str | int
    orientation: float | None = None

    def __str__(self) -> str:
        name = self.waypoint if isinstance(self.waypoint, str) else f"#{integer_text(self.waypoint)}"
        return name if self.orientation is None else f"{name} (facing {self.orientation:g} rad)"


@attrs.frozen
class GoToPlace:
    """Go to a place: the first of ``one_of`` the robot can reach (one place, or the nearest of several)."""

    one_of: tuple[Place, ...]
    followed_by: tuple[Place, ...] = ()
    start_at_departure: bool = False


@attrs.frozen
class PerformAction:
    """Perform ``action``; ``duration_estimate`` in seconds when the description gives one."""

    action: str
    description: Any
    duration_estimate: float | None = None
    use_tool_sink: bool = False
    expected_finish_location: Place | None = None


@attrs.frozen
class Activity:
    """One activity of a sequence: its category and its (not yet read) description."""

    category: str
    description: Any


@attrs.frozen
class Sequence:
    """Activities one after another; each is read under its own category when it starts."""

    activities: tuple[Activity, ...]
    category: str | None = None
    detail: Any = None


@attrs.frozen
class Clean:
    """Clean a zone."""

    zone: str
    type: str | None = None


@attrs.frozen
class PayloadItem:
    """Some number of one item, and the compartment it goes in, if given."""

    sku: str
    quantity: int
    compartment: str | None = None


@attrs.frozen
class PayloadTransfer:
    """Load (``pickup``) or unload (``dropoff``) a payload at a place."""

    kind: str
    place: Place
    payload: tuple[PayloadItem, ...]
    handler: str | None = None


#: What :func:`read` gives.
Reading = GoToPlace | PerformAction | Sequence | Clean | PayloadTransfer


def place(value: Any) -> Place:
    """A place of a conforming description: ``"A"``, ``3`` or ``{"waypoint": ..., "orientation": ...}``."""
    if isinstance(value, dict):
        orientation = value.get("orientation")
        return Place(_waypoint(value["waypoint"]), None if orientation is None else _float(orientation))
    return Place(_waypoint(value))


def _float(value: int | float) -> float:
    """A JSON number as a float; an integer too large for one is infinite, as JSON readers read it."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


def _waypoint(value: Any) -> str | int:
    return value if isinstance(value, str) else int(value)  # 3.0 is the index 3


#: The forms of a go_to_place description, by the index of its schema's ``oneOf`` branch.
PLACE_FORM, PLACE_OBJECT_FORM, ONE_OF_FORM = 0, 1, 2


def _go_to_place(description: Any) -> GoToPlace:
    form = shapes.form("go_to_place", description)  # by the form it fits, not by the keys it has
    if form == ONE_OF_FORM:
        choices = tuple(place(choice) for choice in description["one_of"])
    elif form == PLACE_OBJECT_FORM:
        choices = (place(description["place"]),)
    else:
        return GoToPlace((place(description),))
    return GoToPlace(
        one_of=choices,
        followed_by=tuple(place(item) for item in description.get("followed_by", ())),
        start_at_departure=bool(description.get("start_at_departure", False)),
    )


def _perform_action(description: Any) -> PerformAction:
    millis = description.get("unix_millis_action_duration_estimate")
    finish = description.get("expected_finish_location")
    return PerformAction(
        action=description["category"],
        description=description["description"],
        duration_estimate=None if millis is None else _float(int(millis)) / 1000,
        use_tool_sink=bool(description.get("use_tool_sink", False)),
        expected_finish_location=None if finish is None else place(finish),
    )


def _sequence(description: Any) -> Sequence:
    items = description if isinstance(description, list) else description["activities"]
    activities = tuple(Activity(item["category"], item["description"]) for item in items)
    if isinstance(description, list):
        return Sequence(activities)
    category = description.get("category")
    return Sequence(activities, category=category, detail=description.get("detail"))


def _clean(description: Any) -> Clean:
    return Clean(zone=description["zone"], type=description.get("type"))


def _transfer(kind: str, description: Any) -> PayloadTransfer:
    payload = description["payload"]
    items = payload if isinstance(payload, list) else [payload]
    return PayloadTransfer(
        kind=kind,
        place=place(description["place"]),
        payload=tuple(
            PayloadItem(item["sku"], int(item["quantity"]), item.get("compartment")) for item in items
        ),
        handler=description.get("handler"),
    )


def read(category: str, description: Any) -> Reading:
    """``description`` (parsed JSON) of ``category`` as typed values.

    Raises :class:`~dynevent.errors.UnknownCategory` for a category without a
    schema and :class:`~dynevent.errors.InvalidEventDescription` (with the
    errors) for a description that does not fit its schema.
    """
    if not shapes.conforms(category, description):
        raise InvalidEventDescription(category, shapes.shape_errors(category, description))
    if category == "go_to_place":
        return _go_to_place(description)
    if category == "perform_action":
        return _perform_action(description)
    if category == "sequence":
        return _sequence(description)
    if category == "clean":
        return _clean(description)
    return _transfer(category, description)
