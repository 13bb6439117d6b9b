"""Many robots' servers in one object, routed by ``(fleet, robot)`` or by protocol name.

A :class:`Fleet` holds, for every robot it knows, the robot's
:class:`~dynevent.server.machine.State` and :class:`~dynevent.server.machine.ServerConfig`,
keyed by :class:`RobotKey` ``(fleet, robot)``.  Robots of several fleets may
share one :class:`Fleet`.  It adds nothing to the rules: :meth:`Fleet.step` is
:func:`dynevent.server.machine.step` applied to the held state of one robot.

Routing costs a constant number of dict lookups whatever the number of
robots: by key directly, and by name (an action, topic or service name of
:mod:`dynevent.wire.names`) by splitting the name at its last two ``/`` and looking
up the prefix and the key.  A name that does not route that way is handed to
:func:`dynevent.wire.names.parse_name`, so a malformed name raises the same
:class:`~dynevent.errors.InvalidName` it would raise there.

Configuration: each robot is added with its own config, or takes its fleet's
default (:meth:`Fleet.set_fleet_config`), or else the default of the whole
:class:`Fleet`.  The config is chosen when the robot is added.

Snapshots: :meth:`Fleet.snapshot` writes every robot's state as one JSON
object ``{"format": "dynevent.server.fleet", "version": 1, "robots": [...]}`` whose
items are the per-robot snapshots of :func:`dynevent.server.snapshot.snapshot`, in
the order the robots were added.  Configs are not part of a snapshot (their
validators are callables): :meth:`Fleet.restore` asks a lookup for them.  A
document that is corrupt, of another format or of an unknown version is
refused with :class:`~dynevent.errors.InvalidSnapshot` naming the JSON path,
and no fleet is returned.

A :class:`Fleet` is not thread-safe: a binding whose callbacks run on several
threads takes one lock around each call.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from typing import Any, NamedTuple, TypeAlias

from dynevent.errors import (  # defined there with every error; importable here too
    DuplicateRobot,
    InvalidSnapshot,
    UnknownRobot,
)
from dynevent.server import inputs as ins
from dynevent.server import machine, snapshot
from dynevent.server.machine import ServerConfig, State
from dynevent.server.outputs import Decision, Output
from dynevent.wire import _json
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.names import NameKind, build_name, parse_name, validate_robot, validate_token

__all__ = [
    "FORMAT",
    "VERSION",
    "ConfigLookup",
    "DuplicateRobot",
    "Fleet",
    "RobotKey",
    "Routed",
    "UnknownRobot",
]

#: The ``format`` tag of a fleet snapshot.
FORMAT = "dynevent.server.fleet"
#: The fleet snapshot version this release writes and reads.
VERSION = 1


class RobotKey(NamedTuple):
    """What names one robot in a :class:`Fleet`: its fleet and its own name."""

    fleet: str
    robot: str


class Routed(NamedTuple):
    """What :meth:`Fleet.step_by_name` returns: the robot the input went to, and the step's outputs."""

    key: RobotKey
    outputs: tuple[Output, ...]


#: Given ``(fleet, robot)``, the config to restore that robot with; ``None`` means its default.
ConfigLookup: TypeAlias = Callable[[str, str], ServerConfig | None]

# The prefix of each per-robot name, taken from the builders so the two cannot drift apart.
_KIND_OF_PREFIX: dict[str, NameKind] = {
    build_name(kind, "fleet", "robot").rsplit("/", 2)[0]: kind for kind in NameKind
}


class _Seat:
    """One robot in the fleet: its key, current state and config (mutable, for cheap steps)."""

    __slots__ = ("config", "key", "state")

    def __init__(self, key: RobotKey, state: State, config: ServerConfig) -> None:
        self.key = key
        self.state = state
        self.config = config


def _config(value: object, where: str) -> ServerConfig:
    if not isinstance(value, ServerConfig):
        raise TypeError(f"{where}: expected a ServerConfig, got {type(value).__name__}")
    return value


class Fleet:
    """The servers of many robots, keyed by ``(fleet, robot)``.

    ``config`` is the default config of every robot added without one and
    whose fleet has no default of its own; ``fleet_configs`` gives fleets
    their own default.
    """

    __slots__ = ("_default", "_fleet_configs", "_seats")

    def __init__(
        self,
        config: ServerConfig | None = None,
        *,
        fleet_configs: Mapping[str, ServerConfig] | None = None,
    ) -> None:
        self._default = _config(config, "Fleet config") if config is not None else ServerConfig()
        self._fleet_configs: dict[str, ServerConfig] = {}
        self._seats: dict[tuple[str, str], _Seat] = {}
        for fleet, fleet_config in (fleet_configs or {}).items():
            self.set_fleet_config(fleet, fleet_config)

    # ------------------------------------------------------------------ robots

    def set_fleet_config(self, fleet: str, config: ServerConfig | None) -> None:
        """Make ``config`` the default of robots of ``fleet`` added from now on (``None``: no default).

        Robots already added keep the config they were added with.
        """
        token = validate_token("fleet", fleet)
        if config is None:
            self._fleet_configs.pop(token, None)
        else:
            self._fleet_configs[token] = _config(config, f"config of fleet {token!r}")

    def default_config(self, fleet: str) -> ServerConfig:
        """The config a robot of ``fleet`` added without one gets."""
        return self._fleet_configs.get(fleet, self._default)

    def add(
        self, fleet: str, robot: str, config: ServerConfig | None = None, *, state: State | None = None
    ) -> RobotKey:
        """Add a robot and return its key.

        The robot starts from :meth:`State.new <dynevent.server.machine.State.new>`,
        or from ``state`` (which must belong to this fleet and robot).  Raises
        :class:`~dynevent.errors.InvalidName` if the names are not valid tokens
        or make a protocol name too long, :class:`DuplicateRobot` if the robot
        is already here.
        """
        key = RobotKey(*validate_robot(fleet, robot))  # every name of the robot must exist
        if key in self._seats:
            raise DuplicateRobot(*key)
        chosen = self.default_config(key.fleet) if config is None else _config(config, "config")
        if state is None:
            state = State.new(*key)
        elif not isinstance(state, State) or (state.fleet, state.robot) != key:
            raise ValueError(f"the state given for {key.fleet}/{key.robot} belongs to another robot")
        self._seats[key] = _Seat(key, state, chosen)
        return key

    def remove(self, fleet: str, robot: str) -> State:
        """Remove a robot and return its last state; :class:`UnknownRobot` if it is not here."""
        return self._seats.pop(self._seat(fleet, robot).key).state

    def __len__(self) -> int:
        """How many robots the fleet holds."""
        return len(self._seats)

    def __contains__(self, key: object) -> bool:
        """Whether ``(fleet, robot)`` is here."""
        try:
            return key in self._seats
        except TypeError:  # an unhashable key names no robot
            return False

    def __iter__(self) -> Iterator[RobotKey]:
        """The robots' keys, in the order they were added."""
        return (seat.key for seat in self._seats.values())

    def items(self) -> Iterator[tuple[RobotKey, State]]:
        """Each robot's key and current state, in the order they were added."""
        return ((seat.key, seat.state) for seat in self._seats.values())

    def state(self, fleet: str, robot: str) -> State:
        """The robot's current state (a frozen value)."""
        return self._seat(fleet, robot).state

    def config(self, fleet: str, robot: str) -> ServerConfig:
        """The robot's config."""
        return self._seat(fleet, robot).config

    def set_config(self, fleet: str, robot: str, config: ServerConfig) -> None:
        """Give the robot another config; its state is kept."""
        self._seat(fleet, robot).config = _config(config, "config")

    def _seat(self, fleet: str, robot: str) -> _Seat:
        try:
            return self._seats[(fleet, robot)]
        except (KeyError, TypeError):
            pass
        validate_token("fleet", fleet)  # a malformed name is an InvalidName, not an unknown robot
        validate_token("robot", robot)
        raise UnknownRobot(fleet, robot)

    # ------------------------------------------------------------------ routing

    def route(self, name: str) -> RobotKey:
        """The robot a per-robot action, topic or service name belongs to.

        Accepts what :func:`dynevent.wire.names.parse_name` accepts.  Raises
        :class:`~dynevent.errors.InvalidName` for anything else and
        :class:`UnknownRobot` for a well-formed name of a robot not here.
        """
        if type(name) is str:
            prefix, _, robot = name.rpartition("/")
            prefix, _, fleet = prefix.rpartition("/")
            if prefix[:1] == "/":
                prefix = prefix[1:]
            if prefix in _KIND_OF_PREFIX:
                seat = self._seats.get((fleet, robot))
                if seat is not None:
                    return seat.key
        parsed = parse_name(name)  # raises InvalidName for a malformed name
        return self._seat(parsed.fleet, parsed.robot).key

    def step(self, fleet: str, robot: str, event: ins.Input) -> tuple[Output, ...]:
        """Apply ``event`` to the robot; keep its new state; return the outputs to carry out."""
        try:
            seat = self._seats[(fleet, robot)]
        except (KeyError, TypeError):
            seat = self._seat(fleet, robot)
        transition = machine.step(seat.state, event, seat.config)
        seat.state = transition.state
        return transition.outputs

    def step_by_name(self, name: str, event: ins.Input) -> Routed:
        """Apply ``event`` to the robot that ``name`` (see :meth:`route`) belongs to."""
        key = self.route(name)
        return Routed(key, self.step(key.fleet, key.robot, event))

    def accept(self, fleet: str, robot: str, goal: Goal) -> Decision:
        """Would the robot accept ``goal`` now?  (:func:`dynevent.server.machine.accept`.)"""
        seat = self._seat(fleet, robot)
        return machine.accept(seat.state, goal, seat.config)

    def status_message(self, fleet: str, robot: str, now: int) -> DynamicEventStatus:
        """The status message describing the robot's current state."""
        return machine.status_message(self._seat(fleet, robot).state, now)

    # ------------------------------------------------------------------ snapshots

    def snapshot(self) -> dict[str, Any]:
        """Every robot's state as plain JSON values, with format and version."""
        return {
            "format": FORMAT,
            "version": VERSION,
            "robots": [snapshot.snapshot(seat.state) for seat in self._seats.values()],
        }

    def dumps(self) -> str:
        """The snapshot as JSON text."""
        return _json.dumps(self.snapshot())

    @classmethod
    def restore(
        cls,
        data: object,
        configs: ConfigLookup | None = None,
        *,
        config: ServerConfig | None = None,
        fleet_configs: Mapping[str, ServerConfig] | None = None,
    ) -> Fleet:
        """A new fleet holding the robots of a snapshot.

        ``config`` and ``fleet_configs`` are the new fleet's defaults, as for
        the constructor.  Each robot gets ``configs(fleet, robot)`` when that
        is not ``None``, else its default.  The whole document is checked
        before anything is returned: any fault raises
        :class:`~dynevent.errors.InvalidSnapshot` naming its JSON path.
        """
        if not isinstance(data, dict):
            raise InvalidSnapshot("$", f"expected a JSON object, got {type(data).__name__}")
        if data.get("format") != FORMAT:
            raise InvalidSnapshot("$.format", f"expected {FORMAT!r}, got {data.get('format')!r}")
        version = data.get("version")
        if type(version) is not int or version != VERSION:
            raise InvalidSnapshot(
                "$.version", f"unsupported fleet snapshot version {version!r}; this release reads {VERSION}"
            )
        extra = set(data) - {"format", "version", "robots"}
        if extra:
            raise InvalidSnapshot("$", f"unknown keys {sorted(extra)}")
        robots = data.get("robots")
        if not isinstance(robots, list):
            raise InvalidSnapshot("$.robots", f"expected an array, got {type(robots).__name__}")
        fleet = cls(config, fleet_configs=fleet_configs)
        for index, item in enumerate(robots):
            where = f"$.robots[{index}]"
            try:
                state = snapshot.restore(item)
            except InvalidSnapshot as exc:
                raise InvalidSnapshot(where + exc.path[1:], exc.problem) from None
            key = (state.fleet, state.robot)
            if key in fleet._seats:
                raise InvalidSnapshot(where, f"robot {state.robot!r} of fleet {state.fleet!r} appears twice")
            chosen = None if configs is None else configs(*key)
            seat = RobotKey(*key)  # restore checked every name of the robot (R19.8)
            config_of = fleet.default_config(seat.fleet) if chosen is None else _config(chosen, "config")
            fleet._seats[seat] = _Seat(seat, state, config_of)
        return fleet

    @classmethod
    def loads(
        cls,
        text: str | bytes | bytearray,
        configs: ConfigLookup | None = None,
        *,
        config: ServerConfig | None = None,
        fleet_configs: Mapping[str, ServerConfig] | None = None,
    ) -> Fleet:
        """A new fleet from fleet snapshot JSON text (see :meth:`restore`)."""
        try:
            data = _json.parse(text, bounded=False)  # restore decodes against the snapshot's schema
        except _json.JsonProblem as exc:
            raise InvalidSnapshot("$", str(exc)) from None
        return cls.restore(data, configs, config=config, fleet_configs=fleet_configs)

    def __repr__(self) -> str:
        return f"<Fleet of {len(self._seats)} robots>"
