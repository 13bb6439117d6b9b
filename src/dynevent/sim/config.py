"""The configuration of the fleet ``dynevent serve`` simulates, read and checked without ROS 2.

What a ``--config`` file and the flags say (the fleet, its robots, the
simulated categories, the robots' map and actions, the mode, the shard), so
that ``dynevent serve`` checks its own input, and says what is wrong with it,
before it needs rclpy; and what a simulated child does with its description
(:func:`plan`).
"""

from __future__ import annotations

import re
import zlib
from collections.abc import Sequence
from typing import Any

import attrs

from dynevent import descriptions, files
from dynevent.descriptions import shapes
from dynevent.errors import FileError, InvalidConfig, InvalidName, MissingExtra, ServeError, short_repr
from dynevent.server.machine import ServerConfig, State, Validator, any_description
from dynevent.wire._fields import U32_MAX
from dynevent.wire.names import validate_token
from dynevent.wire.vocab import Compatibility, IdPolicy

__all__ = [
    "DEFAULT_CATEGORIES",
    "DEFAULT_DESCRIPTION",
    "CategorySpec",
    "ServeConfig",
    "Step",
    "load_config",
    "machine_config",
    "parse_shard",
    "plan",
    "shard_of",
]


#: The compatibility modes, as the command line and a ``--config`` file name them.
_MODES = tuple(mode.value for mode in Compatibility)


def _mode(value: Any) -> Compatibility:
    """A compatibility mode, given as the enum or its name; :class:`ServeError` for any other value."""
    if isinstance(value, Compatibility) or value in _MODES:
        return Compatibility(value)
    raise _wrong("compatibility", "", f"one of {', '.join(_MODES)}", value)


#: The description of the dynamic events the simulated fleet begins (a begin command may give another).
DEFAULT_DESCRIPTION = '{"category": "dynevent_serve", "detail": "a simulated dynamic event"}'


@attrs.frozen
class CategorySpec:
    """How a simulated child of one category behaves: how long it takes (a ``perform_action`` takes
    its duration estimate when it gives one), how often it reports, and the places it fails on."""

    duration: float = 3.0
    report_every: float = 1.0
    fail_on: tuple[str, ...] = ()


DEFAULT_CATEGORIES = {
    "go_to_place": CategorySpec(duration=3.0, report_every=1.0, fail_on=("nowhere",)),
    "perform_action": CategorySpec(duration=2.0, report_every=1.0),
    "sequence": CategorySpec(duration=0.0, report_every=1.0),
    "clean": CategorySpec(duration=5.0, report_every=1.0),
    "pickup": CategorySpec(duration=2.0, report_every=1.0),
    "dropoff": CategorySpec(duration=2.0, report_every=1.0),
}


@attrs.frozen
class ServeConfig:
    """What ``dynevent serve`` runs: the fleet, its robots, the categories and the options."""

    fleet: str = "tinyRobot"
    robots: tuple[str, ...] = ("tinyRobot1",)
    categories: dict[str, CategorySpec] = attrs.field(factory=lambda: dict(DEFAULT_CATEGORIES))
    compatibility: Compatibility = attrs.field(default=Compatibility.STANDARD, converter=_mode)
    rebegin: float = 2.0
    #: The seq of each robot's first run (a robot restored from ``--state`` keeps its own): start at
    #: 4294967295 to see the seq wrap to 0 at the next begin (R3.2).
    first_seq: int = 1
    #: The robots' map (waypoint names by index, None for an unnamed one) and the actions they
    #: perform; None: every place and every action exists.
    places: tuple[str | None, ...] | None = None
    actions: tuple[str, ...] | None = None
    #: This process's part of the fleet, (K, N): the robots whose name hashes to K of N (1 <= K <= N).
    shard: tuple[int, int] = (1, 1)

    def served(self) -> tuple[str, ...]:
        """The robots this process serves: its shard of the fleet's robots."""
        index, count = self.shard
        return tuple(robot for robot in self.robots if shard_of(robot, count) == index)

    def first_state(self, robot: str) -> State:
        """A robot's state before its first run: the begin that follows gives it :attr:`first_seq`."""
        return attrs.evolve(State.new(self.fleet, robot), seq=(self.first_seq - 1) & U32_MAX)

    @property
    def offers_description(self) -> bool:
        """Whether the robots answer the description query (R16): not in rmf_ros2 mode, as rmf_ros2
        offers none (D17)."""
        return self.compatibility is not Compatibility.RMF_ROS2


#: A shard's numbers: ASCII digits (``str.isdigit`` takes ``²`` too), at most six of them.
_DIGITS = re.compile(r"[0-9]{1,6}")


def shard_of(robot: str, count: int) -> int:
    """The shard (1 to ``count``) that serves ``robot``: the same in every process and on every host."""
    return zlib.crc32(robot.encode("utf-8")) % count + 1


def parse_shard(text: str) -> tuple[int, int]:
    """``"K/N"`` as (K, N), 1 <= K <= N; raises :class:`ServeError` naming the value."""
    index, slash, count = text.partition("/")
    if slash and _DIGITS.fullmatch(index) and _DIGITS.fullmatch(count) and 1 <= int(index) <= int(count):
        return int(index), int(count)
    raise ServeError(f"--shard {text!r}: expected K/N with 1 <= K <= N, e.g. 1/2")


def load_config(
    path: str | None = None,
    *,
    fleet: str | None = None,
    robots: Sequence[str] = (),
    rebegin: float | None = None,
    first_seq: Any = None,
    compatibility: str | None = None,
    shard: str | None = None,
) -> ServeConfig:
    """The configuration from the file at ``path`` (``--config``) and the flags (which win over it);
    raises :class:`ServeError` naming the file's field or the flag."""
    config = ServeConfig()
    if path is not None:
        try:
            data = files.read_json(path, "--config")
        except FileError as exc:
            raise ServeError(str(exc)) from None
        config = _config_from_dict(data, path)
    if fleet is not None:
        config = attrs.evolve(config, fleet=fleet)
    if robots:
        config = attrs.evolve(config, robots=tuple(robots))
    if rebegin is not None:
        config = attrs.evolve(config, rebegin=_seconds("--rebegin", "", rebegin, zero=True))
    if first_seq is not None:
        config = attrs.evolve(config, first_seq=_seq(first_seq, "--first-seq"))
    if compatibility is not None:
        if compatibility not in _MODES:
            raise _wrong("--compatibility", "", f"one of {', '.join(_MODES)}", compatibility)
        config = attrs.evolve(config, compatibility=compatibility)
    if shard is not None:
        config = attrs.evolve(config, shard=parse_shard(shard))
    try:
        validate_token("fleet", config.fleet)
        for robot in config.robots:
            validate_token("robot", robot)
    except InvalidName as exc:
        raise ServeError(str(exc)) from None
    if len(set(config.robots)) != len(config.robots):
        raise ServeError(f"robots: a robot is named twice in {list(config.robots)}")
    try:
        machine_config(config)
        shapes.require_explanations()  # a client author is told where a description goes wrong
    except (InvalidConfig, MissingExtra) as exc:
        raise ServeError(str(exc)) from None
    return config


def machine_config(config: ServeConfig) -> ServerConfig:
    """The machine's configuration of every robot: the field's categories checked as R4.18 says
    (with the configured map and actions), the others taking any description."""
    field = [name for name in config.categories if name in descriptions.CATEGORIES]
    others: dict[str, Validator] = {
        name: any_description for name in config.categories if name not in descriptions.CATEGORIES
    }
    robot = descriptions.Robot(places=config.places, actions=config.actions, categories=field)
    validators = robot.validators(others)
    if config.compatibility is Compatibility.RMF_ROS2:
        return ServerConfig.rmf_ros2(validators)
    return ServerConfig(categories=validators, id_policy=IdPolicy.GOAL, compatibility=config.compatibility)


@attrs.frozen
class Step:
    """A part of a simulated child: what it does (a log line says it), for how many seconds, and
    the error it fails with when it reaches a place its category fails on."""

    label: str
    duration: float
    failure: str | None = None


def plan(category: str, description: Any, config: ServeConfig) -> list[Step]:
    """What a simulated child of ``category`` does with its (accepted, parsed) description: its steps,
    in order; a sequence's activities one after another."""
    spec = config.categories.get(category, CategorySpec())
    if category not in descriptions.CATEGORIES:
        return [Step(category, spec.duration)]
    reading = descriptions.read(category, description)
    if isinstance(reading, descriptions.GoToPlace):
        reachable = _reachable(reading, spec)
        target = (reachable or list(reading.one_of))[0]
        after = (
            f", then {', '.join(str(place) for place in reading.followed_by)}" if reading.followed_by else ""
        )
        failure = None if reachable else f"{target}: no such place"
        return [Step(f"{category} {target}{after}", spec.duration, failure)]
    if isinstance(reading, descriptions.PerformAction):
        estimate = reading.duration_estimate
        seconds = spec.duration if estimate is None else min(max(estimate, 0.001), 86_400.0)
        return [Step(f"{category} {reading.action}", seconds)]
    if isinstance(reading, descriptions.Sequence):
        steps = []
        for number, activity in enumerate(reading.activities, start=1):
            for step in plan(activity.category, activity.description, config):
                label = f"activity {number} of {len(reading.activities)}: {step.label}"
                steps.append(attrs.evolve(step, label=label))
        return steps or [Step(f"{category} (no activities)", 0.001)]
    if isinstance(reading, descriptions.Clean):
        return [Step(f"{category} {reading.zone}", spec.duration)]
    items = sum(item.quantity for item in reading.payload)
    failure = f"{reading.place}: no such place" if str(reading.place.waypoint) in spec.fail_on else None
    label = f"{category} at {reading.place} ({items} item{'s' if items != 1 else ''})"
    return [Step(label, spec.duration, failure)]


def _reachable(reading: descriptions.GoToPlace, spec: CategorySpec) -> list[Any]:
    """The places of a go_to_place the simulated robot can reach, in order: it goes to the first."""
    return [place for place in reading.one_of if str(place.waypoint) not in spec.fail_on]


def destination(category: str, description: Any, config: ServeConfig) -> str | None:
    """Where a simulated go_to_place child leaves the robot (the first place it can reach, then its
    last ``followed_by``), as :func:`plan` runs it; None for another category or a place it cannot
    reach.  A description that is not a go_to_place the simulation can read is None too."""
    if category != "go_to_place":
        return None
    try:
        reading = descriptions.read(category, description)
    except Exception:  # a defect here must only leave the robot's place unknown
        return None
    if not isinstance(reading, descriptions.GoToPlace):
        return None
    reachable = _reachable(reading, config.categories.get(category, CategorySpec()))
    if not reachable:
        return None
    return str(reading.followed_by[-1] if reading.followed_by else reachable[0])


def _seq(value: Any, what: str) -> int:
    """A run's seq (0 to 4294967295); raises :class:`ServeError` naming ``what`` and the value."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2**32:
        raise ServeError(f"{what}: expected a seq from 0 to 4294967295 (got {value!r})")
    return value


#: The keys a ``--config`` file may have, and those of each of its categories.
_KEYS = ("fleet", "robots", "categories", "compatibility", "rebegin", "first_seq", "places", "actions")
_CATEGORY_KEYS = ("duration", "report_every", "fail_on")
#: The longest a simulated step or a re-begin may be configured to take (seconds: a day).
_LONGEST = 86_400.0


def _wrong(source: str, where: str, expected: str, value: Any) -> ServeError:
    """The one line of a wrong value: the file and field (or the flag), what was expected, the value."""
    at = f"{source}: {where}" if where else source
    return ServeError(f"{at}: expected {expected} (got {short_repr(value)})")


def _seconds(source: str, where: str, value: Any, *, zero: bool = False) -> float:
    """A number of seconds, above 0 (or 0 itself when ``zero``) and at most a day."""
    low = "0" if zero else "above 0"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _wrong(source, where, f"a number of seconds, {low} and at most {_LONGEST:g}", value)
    # comparisons before float(): an integer of any size is judged exactly, and NaN fails both
    if not (value >= 0 if zero else value > 0) or not value <= _LONGEST:
        raise _wrong(source, where, f"a number of seconds, {low} and at most {_LONGEST:g}", value)
    return float(value)


def _string_list(source: str, where: str, value: Any, what: str, *, nulls: bool = False) -> tuple[Any, ...]:
    fits = (str, type(None)) if nulls else str
    if not isinstance(value, list) or not all(isinstance(item, fits) for item in value):
        raise _wrong(source, where, what, value)
    return tuple(value)


def _category(source: str, name: str, spec: Any) -> CategorySpec:
    where = f"categories.{name}"
    if not isinstance(spec, dict):
        raise _wrong(source, where, "an object of duration, report_every and fail_on", spec)
    unknown = sorted(set(spec) - set(_CATEGORY_KEYS))
    if unknown:
        raise ServeError(f"{source}: {where}: unknown keys {unknown}")
    default = DEFAULT_CATEGORIES.get(name, CategorySpec())
    return CategorySpec(
        duration=_seconds(source, f"{where}.duration", spec.get("duration", default.duration or 3.0)),
        report_every=_seconds(
            source, f"{where}.report_every", spec.get("report_every", default.report_every)
        ),
        fail_on=_string_list(
            source, f"{where}.fail_on", spec.get("fail_on", list(default.fail_on)), "a list of place names"
        ),
    )


def _config_from_dict(data: Any, source: str) -> ServeConfig:
    if not isinstance(data, dict):
        raise _wrong(source, "the file", "a JSON object", data)
    unknown = sorted(set(data) - set(_KEYS))
    if unknown:
        raise ServeError(f"{source}: unknown keys {unknown}")
    categories = dict(DEFAULT_CATEGORIES)
    if "categories" in data:
        if not isinstance(data["categories"], dict):
            raise _wrong(source, "categories", "an object of category names", data["categories"])
        categories = {name: _category(source, name, spec) for name, spec in data["categories"].items()}
    places, actions = data.get("places"), data.get("actions")
    for key in ("fleet", "compatibility"):
        if key in data and not isinstance(data[key], str):
            raise _wrong(source, key, "a string", data[key])
    compatibility = data.get("compatibility", "standard")
    if compatibility not in _MODES:
        raise _wrong(source, "compatibility", f"one of {', '.join(_MODES)}", compatibility)
    return ServeConfig(
        fleet=data.get("fleet", "tinyRobot"),
        robots=_string_list(source, "robots", data.get("robots", ["tinyRobot1"]), "a list of names"),
        categories=categories,
        compatibility=compatibility,
        rebegin=_seconds(source, "rebegin", data.get("rebegin", 2.0), zero=True),
        first_seq=_seq(data.get("first_seq", 1), f"{source}: first_seq"),
        places=None
        if places is None
        else _string_list(
            source, "places", places, "a list of waypoint names (null for an unnamed waypoint)", nulls=True
        ),
        actions=None
        if actions is None
        else _string_list(source, "actions", actions, "a list of action names"),
    )
