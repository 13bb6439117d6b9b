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

import itertools
from collections.abc import Iterable, Iterator, Mapping
from typing import Any

import attrs

from dynevent.descriptions import reading, shapes
from dynevent.descriptions._explain import pointer, prefixed, render, under
from dynevent.descriptions._suggest import Suggestions
from dynevent.errors import InvalidConfig
from dynevent.server.machine import Validator, listed_errors
from dynevent.wire._json import MAX_DEPTH

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
    names = tuple(value)
    for name in names:
        if not isinstance(name, str) or not name:
            raise InvalidConfig(field, name, "expected a non-empty name", owner="Robot")
    return frozenset(names)


def _actions(value: Any) -> frozenset[str] | None:
    return _names(value, "actions")


def _categories(value: Any) -> tuple[str, ...]:
    if isinstance(value, bytes) or not isinstance(value, (str, Iterable)):
        raise InvalidConfig("categories", value, "expected a list of category names", owner="Robot")
    categories = tuple(value) if not isinstance(value, str) else (value,)
    for category in categories:
        if not isinstance(category, str) or category not in shapes.CATEGORIES:
            raise InvalidConfig(
                "categories",
                category,
                f"expected categories from {', '.join(shapes.CATEGORIES)}",
                owner="Robot",
            )
    return categories


#: The unknown names of one check that get a did-you-mean (R4.19: a suggestion costs more than a
#: look-up, so a goal of many unknown names is not a goal of many suggestions).
MAX_SUGGESTIONS = 3
#: Stands for "the robot's own validator" where a check has no table of validators.
_OWN = object()


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
    _suggestions: Suggestions = attrs.field(init=False, eq=False, repr=False)

    def __attrs_post_init__(self) -> None:
        index = {name: number for number, name in enumerate(self.places or ()) if name is not None}
        object.__setattr__(self, "_index", index)
        object.__setattr__(self, "_suggestions", Suggestions(index))

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
        else what is not on its map or in its abilities, the two steps of the fleet adapter (R4.18);
        empty when it accepts it.  At most
        :data:`~dynevent.server.machine.MAX_LISTED_ERRORS` faults are listed (R4.19), found in time
        linear in the description's size."""
        return listed_errors(self._faults(category, description, _Judging(None)))

    def validators(self, extra: Mapping[str, Validator] | None = None) -> dict[str, Validator]:
        """A validator for each of the robot's categories, and ``extra``'s besides: a
        :class:`~dynevent.server.machine.ServerConfig`'s ``categories``.  A sequence's activities
        may be of any category in the result, ``extra``'s included."""
        table: dict[str, Validator] = {}

        def validate(category: str, description: Any) -> tuple[str, ...]:
            return listed_errors(self._faults(category, description, _Judging(table, validate)))

        table.update(dict.fromkeys(self.categories, validate))
        table.update(extra or {})
        return table

    # ------------------------------------------------------------------------------------ checks

    def _faults(self, category: str, description: Any, judging: _Judging, depth: int = 0) -> Iterator[str]:
        """The faults of ``description``, found one at a time (the caller stops reading when it has
        listed enough)."""
        if category not in self.categories:
            yield f"/: {render(category)} is not a category this robot supports ({_listed(self.categories)})"
            return
        faults = shapes.shape_errors(category, description)
        if faults:
            yield from faults
        elif category == "sequence":
            yield from self._sequence(description, judging, depth)
        elif category == "perform_action":
            yield from self._perform_action(description, judging)
        elif self.places is None or category == "clean":
            return
        elif category == "go_to_place":
            yield from self._go_to_place(description, judging)
        else:
            yield from self._place(description["place"], ["place"], judging)  # pickup, dropoff

    def _place(self, place: Any, path: list[Any], judging: _Judging) -> Iterator[str]:
        if isinstance(place, dict):
            place, path = place["waypoint"], [*path, "waypoint"]
        waypoint = place if isinstance(place, str) else int(place)
        if self.knows(waypoint):
            return
        where = pointer(path)
        if isinstance(waypoint, str):
            close = self._suggestions.closest(waypoint) if judging.may_suggest() else None
            hint = f" (did you mean {render(close)}?)" if close is not None else ""
            yield f"{where}: {render(waypoint)} is not a waypoint on this robot's map{hint}"
            return
        count = len(self.places or ())
        span = f"its waypoints are 0 to {count - 1}" if count else "it has no waypoints"
        yield f"{where}: waypoint {render(waypoint)} is not on this robot's map ({span})"

    def _go_to_place(self, description: Any, judging: _Judging) -> Iterator[str]:
        # by the form it fits, not by the keys it has (_faults saw it conform)
        form = shapes.form("go_to_place", description, conforming=True)
        places: Iterable[tuple[Any, list[Any]]]
        if form == reading.ONE_OF_FORM:
            places = ((place, ["one_of", number]) for number, place in enumerate(description["one_of"]))
        elif form == reading.PLACE_OBJECT_FORM:
            places = itertools.chain(
                [(description["place"], ["place"])],
                ((place, ["followed_by", n]) for n, place in enumerate(description.get("followed_by", ()))),
            )
        else:
            places = [(description, [])]
        for place, path in places:
            yield from self._place(place, path, judging)

    def _perform_action(self, description: Any, judging: _Judging) -> Iterator[str]:
        action = description["category"]
        if self.actions is not None and action not in self.actions:
            performs = _listed(self.actions)
            yield f"/category: {render(action)} is not an action this robot performs ({performs})"
        finish = description.get("expected_finish_location")
        if finish is not None and self.places is not None:
            yield from self._place(finish, ["expected_finish_location"], judging)

    def _sequence(self, description: Any, judging: _Judging, depth: int) -> Iterator[str]:
        nested = isinstance(description, dict)
        activities = description["activities"] if nested else description
        if judging.table is not None:
            supported: Mapping[str, Any] = judging.table
        else:
            supported = dict.fromkeys(self.categories, judging.own)
        for number, activity in enumerate(activities):
            at = ["activities", number] if nested else [number]
            category = activity["category"]
            validate = supported.get(category)
            if validate is None and self.open_sequences:
                continue
            if validate is None:
                yield (
                    f"{pointer([*at, 'category'])}: {render(category)} is not a category this robot "
                    f"supports ({_listed(supported)})"
                )
                continue
            where = [*at, "description"]
            if validate is not judging.own:
                yield from prefixed(where, listed_errors(validate(category, activity["description"])))
            elif depth >= MAX_DEPTH:  # each level of activities is deeper in the goal's JSON too
                yield f"{pointer(where)}: sequences nested deeper than {MAX_DEPTH} levels"
            else:
                inner = self._faults(category, activity["description"], judging, depth + 1)
                yield from (under(pointer(where), line) for line in inner)


@attrs.define
class _Judging:
    """One check's bookkeeping: the categories a sequence's activities may use (``None``: the
    robot's own), the robot's own validator in that table, and the suggestions still to make."""

    table: Mapping[str, Validator] | None
    own: Any = _OWN
    suggestions_left: int = MAX_SUGGESTIONS

    def may_suggest(self) -> bool:
        """Whether the next unknown name gets a did-you-mean (only the first few do, R4.19)."""
        self.suggestions_left -= 1
        return self.suggestions_left >= 0


def shape_validators() -> dict[str, Validator]:
    """Validators that refuse only what every server refuses: a description of a field category that
    its schema does not accept (in a sequence, each activity of a field category by its own schema;
    an activity of another category is the server's to judge).  What a client that knows nothing of
    the robot checks before it sends a goal (``dynevent send``)."""
    return Robot(open_sequences=True).validators()
