"""What one robot can do: the places on its map, the actions it performs, the categories it supports.

A description that fits its category's schema may still be one the robot
cannot carry out: a waypoint that is not on its navigation graph, an action
its fleet never declared, an activity of a sequence in a category it does not
support.  The deployed fleet adapter finds these when it reads the
description for the robot; :class:`Robot` does the same, after the schema,
and names what is unknown.  Its :meth:`Robot.validators` are what a
:class:`~dynevent.server.machine.ServerConfig` takes as ``categories``.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Mapping
from typing import Any

import attrs

from dynevent.descriptions import reading, shapes
from dynevent.descriptions._explain import pointer, prefixed, render
from dynevent.errors import InvalidConfig
from dynevent.server.machine import Validator

__all__ = ["Robot", "shape_validators"]


def _places(value: Any) -> tuple[str | None, ...] | None:
    if value is None:
        return None
    if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
        raise InvalidConfig(
            "places", value, "expected a list of waypoint names (null for an unnamed waypoint)", owner="Robot"
        )
    places = tuple(value)
    seen: set[str] = set()
    for index, name in enumerate(places):
        if name is not None and (not isinstance(name, str) or not name):
            raise InvalidConfig("places", name, f"waypoint {index}: expected a name or null", owner="Robot")
        if name is not None and name in seen:
            raise InvalidConfig(
                "places", name, f"waypoint {index}: a name is given to two waypoints", owner="Robot"
            )
        if name is not None:
            seen.add(name)
    return places


def _names(value: Any, field: str) -> frozenset[str] | None:
    if value is None:
        return None
    if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
        raise InvalidConfig(field, value, "expected a list of names", owner="Robot")
    names = frozenset(value)
    for name in names:
        if not isinstance(name, str) or not name:
            raise InvalidConfig(field, name, "expected a non-empty name", owner="Robot")
    return names


def _actions(value: Any) -> frozenset[str] | None:
    return _names(value, "actions")


def _categories(value: Any) -> tuple[str, ...]:
    categories = tuple(value) if not isinstance(value, str) else (value,)
    for category in categories:
        if category not in shapes.CATEGORIES:
            raise InvalidConfig(
                "categories",
                category,
                f"expected categories from {', '.join(shapes.CATEGORIES)}",
                owner="Robot",
            )
    return categories


def _listed(names: Iterable[str]) -> str:
    return ", ".join(render(name) for name in sorted(names)) or "none"


@attrs.frozen
class Robot:
    """A robot's map, actions and categories; ``None`` for places or actions means "every one exists".

    ``places`` is the robot's navigation graph as a list: the waypoint of index
    ``i`` is ``places[i]``, its name, or ``None`` when it has none (a place may
    name a waypoint by either).  ``actions`` are the ``perform_action``
    categories its fleet performs.  ``categories`` are the description
    categories it supports (by default every one :mod:`dynevent.descriptions`
    has a schema for).  A bad value raises :class:`~dynevent.errors.InvalidConfig`.
    """

    places: tuple[str | None, ...] | None = attrs.field(default=None, converter=_places)
    actions: frozenset[str] | None = attrs.field(default=None, converter=_actions)
    categories: tuple[str, ...] = attrs.field(default=shapes.CATEGORIES, converter=_categories)
    #: Whether a sequence's activity of a category this robot does not know passes (its description
    #: unchecked): for a client, which cannot know the categories a server adds (:func:`shape_validators`).
    open_sequences: bool = False
    _index: Mapping[str, int] = attrs.field(init=False, eq=False, repr=False)

    def __attrs_post_init__(self) -> None:
        index = {name: number for number, name in enumerate(self.places or ()) if name is not None}
        object.__setattr__(self, "_index", index)

    def knows(self, waypoint: str | int) -> bool:
        """Whether a waypoint of that name or index is on this robot's map (with no map given,
        every one is)."""
        if self.places is None:
            return True
        if isinstance(waypoint, str):
            return waypoint in self._index
        return 0 <= waypoint < len(self.places)

    def check(self, category: str, description: Any) -> tuple[str, ...]:
        """Why this robot refuses ``description`` (parsed JSON) of ``category``: the schema's faults,
        else what is not on its map or in its abilities; empty when it accepts it."""
        return self._check(category, description, None)

    def validators(self, extra: Mapping[str, Validator] | None = None) -> dict[str, Validator]:
        """A validator for each of the robot's categories, and ``extra``'s besides: a
        :class:`~dynevent.server.machine.ServerConfig`'s ``categories``.  A sequence's activities
        may be of any category in the result, ``extra``'s included."""
        table: dict[str, Validator] = {}

        def validate(category: str, description: Any) -> tuple[str, ...]:
            return self._check(category, description, table)

        table.update(dict.fromkeys(self.categories, validate))
        table.update(extra or {})
        return table

    # ------------------------------------------------------------------------------------ checks

    def _check(
        self, category: str, description: Any, table: Mapping[str, Validator] | None
    ) -> tuple[str, ...]:
        if category not in self.categories:
            return (
                f"/: {render(category)} is not a category this robot supports ({_listed(self.categories)})",
            )
        faults = shapes.shape_errors(category, description)
        if faults:
            return faults
        if category == "sequence":
            return self._sequence(description, table)
        if category == "perform_action":
            return self._perform_action(description)
        if self.places is None or category == "clean":
            return ()
        if category == "go_to_place":
            return self._go_to_place(description)
        return self._place(description["place"], ["place"])  # pickup, dropoff

    def _place(self, place: Any, path: list[Any]) -> tuple[str, ...]:
        if isinstance(place, dict):
            place, path = place["waypoint"], [*path, "waypoint"]
        waypoint = place if isinstance(place, str) else int(place)
        if self.knows(waypoint):
            return ()
        where = pointer(path)
        if isinstance(waypoint, str):
            close = difflib.get_close_matches(waypoint, list(self._index), n=1)
            hint = f" (did you mean {render(close[0])}?)" if close else ""
            return (f"{where}: {render(waypoint)} is not a waypoint on this robot's map{hint}",)
        count = len(self.places or ())
        span = f"its waypoints are 0 to {count - 1}" if count else "it has no waypoints"
        return (f"{where}: waypoint {render(waypoint)} is not on this robot's map ({span})",)

    def _go_to_place(self, description: Any) -> tuple[str, ...]:
        form = shapes.form("go_to_place", description)  # by the form it fits, not by the keys it has
        if form == reading.ONE_OF_FORM:
            places = [(place, ["one_of", number]) for number, place in enumerate(description["one_of"])]
        elif form == reading.PLACE_OBJECT_FORM:
            places = [(description["place"], ["place"])]
            places += [
                (place, ["followed_by", n]) for n, place in enumerate(description.get("followed_by", ()))
            ]
        else:
            places = [(description, [])]
        return tuple(fault for place, path in places for fault in self._place(place, path))

    def _perform_action(self, description: Any) -> tuple[str, ...]:
        faults: tuple[str, ...] = ()
        action = description["category"]
        if self.actions is not None and action not in self.actions:
            faults = (
                f"/category: {render(action)} is not an action this robot performs ({_listed(self.actions)})",
            )
        finish = description.get("expected_finish_location")
        if finish is not None and self.places is not None:
            faults += self._place(finish, ["expected_finish_location"])
        return faults

    def _sequence(self, description: Any, table: Mapping[str, Validator] | None) -> tuple[str, ...]:
        nested = isinstance(description, dict)
        activities = description["activities"] if nested else description
        faults: list[str] = []
        supported = table if table is not None else dict.fromkeys(self.categories, self.check)
        for number, activity in enumerate(activities):
            at = ["activities", number] if nested else [number]
            category = activity["category"]
            validate = supported.get(category)
            if validate is None and self.open_sequences:
                continue
            if validate is None:
                faults.append(
                    f"{pointer([*at, 'category'])}: {render(category)} is not a category this robot "
                    f"supports ({_listed(supported)})"
                )
                continue
            faults.extend(prefixed([*at, "description"], validate(category, activity["description"])))
        return tuple(faults)


def shape_validators() -> dict[str, Validator]:
    """Validators that refuse only what every server refuses: a description of a field category that
    its schema does not accept (in a sequence, each activity of a field category by its own schema;
    an activity of another category is the server's to judge).  What a client that knows nothing of
    the robot checks before it sends a goal (``dynevent send``)."""
    return Robot(open_sequences=True).validators()
