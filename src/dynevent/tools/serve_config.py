"""``dynevent serve``'s configuration, read and checked without ROS 2.

What a ``--config`` file and the flags say (the fleet, its robots, the
simulated categories, the mode, the shard), so that ``dynevent serve`` checks
its own input, and says what is wrong with it, before it needs rclpy.
"""

from __future__ import annotations

import argparse
import json
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import attrs

from dynevent.errors import InvalidName, ServeError
from dynevent.wire.names import validate_token

__all__ = [
    "DEFAULT_CATEGORIES",
    "CategorySpec",
    "ServeConfig",
    "load_config",
    "parse_shard",
    "place_of",
    "shard_of",
    "validator",
]


@attrs.frozen
class CategorySpec:
    """How a simulated child of one category behaves."""

    duration: float = 3.0
    report_every: float = 1.0
    fail_on: tuple[str, ...] = ()
    needs_place: bool = False


DEFAULT_CATEGORIES = {
    "go_to_place": CategorySpec(duration=3.0, report_every=1.0, fail_on=("nowhere",), needs_place=True),
    "perform_action": CategorySpec(duration=2.0, report_every=1.0),
}


@attrs.frozen
class ServeConfig:
    """What ``dynevent serve`` runs: the fleet, its robots, the categories and the options."""

    fleet: str = "tinyRobot"
    robots: tuple[str, ...] = ("tinyRobot1",)
    categories: dict[str, CategorySpec] = attrs.field(factory=lambda: dict(DEFAULT_CATEGORIES))
    compatibility: str = "standard"
    rebegin: float = 2.0
    #: This process's part of the fleet, (K, N): the robots whose name hashes to K of N (1 <= K <= N).
    shard: tuple[int, int] = (1, 1)

    def served(self) -> tuple[str, ...]:
        """The robots this process serves: its shard of the fleet's robots."""
        index, count = self.shard
        return tuple(robot for robot in self.robots if shard_of(robot, count) == index)


def shard_of(robot: str, count: int) -> int:
    """The shard (1 to ``count``) that serves ``robot``: the same in every process and on every host."""
    return zlib.crc32(robot.encode("utf-8")) % count + 1


def parse_shard(text: str) -> tuple[int, int]:
    """``"K/N"`` as (K, N), 1 <= K <= N; raises :class:`ServeError` naming the value."""
    index, slash, count = text.partition("/")
    if slash and index.isdigit() and count.isdigit() and 1 <= int(index) <= int(count):
        return int(index), int(count)
    raise ServeError(f"--shard {text!r}: expected K/N with 1 <= K <= N, e.g. 1/2")


def place_of(description: Any) -> str | None:
    """The place a ``go_to_place`` description names: a string, ``{"place": P}`` or ``{"one_of": [P...]}``."""
    if isinstance(description, str) and description:
        return description
    if isinstance(description, dict):
        if isinstance(description.get("place"), str):
            return str(description["place"])
        choices = description.get("one_of")
        if isinstance(choices, list) and choices:
            first = choices[0]
            if isinstance(first, str):
                return first
            if isinstance(first, dict) and isinstance(first.get("waypoint"), str):
                return str(first["waypoint"])
    return None


def validator(spec: CategorySpec) -> Callable[[str, Any], list[str]]:
    def validate(category: str, description: Any) -> list[str]:
        if spec.needs_place and place_of(description) is None:
            return ['expected a place: "P", {"place": "P"} or {"one_of": ["P", ...]}']
        return []

    return validate


def load_config(args: argparse.Namespace) -> ServeConfig:
    """The configuration from ``--config FILE`` and the flags (flags win); raises :class:`ServeError`."""
    config = ServeConfig()
    if args.config is not None:
        try:
            data = json.loads(Path(args.config).read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise ServeError(f"--config {args.config}: {exc}") from None
        config = _config_from_dict(data, args.config)
    if args.fleet is not None:
        config = attrs.evolve(config, fleet=args.fleet)
    if args.robots:
        config = attrs.evolve(config, robots=tuple(args.robots))
    if args.rebegin is not None:
        config = attrs.evolve(config, rebegin=args.rebegin)
    if getattr(args, "compatibility", None) is not None:
        config = attrs.evolve(config, compatibility=args.compatibility)
    if getattr(args, "shard", None) is not None:
        config = attrs.evolve(config, shard=parse_shard(args.shard))
    try:
        validate_token("fleet", config.fleet)
        for robot in config.robots:
            validate_token("robot", robot)
    except InvalidName as exc:
        raise ServeError(str(exc)) from None
    if len(set(config.robots)) != len(config.robots):
        raise ServeError(f"robots: a robot is named twice in {list(config.robots)}")
    return config


def _config_from_dict(data: Any, source: str) -> ServeConfig:
    if not isinstance(data, dict):
        raise ServeError(f"{source}: expected a JSON object")
    unknown = set(data) - {"fleet", "robots", "categories", "compatibility", "rebegin"}
    if unknown:
        raise ServeError(f"{source}: unknown keys {sorted(unknown)}")
    categories = dict(DEFAULT_CATEGORIES)
    if "categories" in data:
        categories = {}
        for name, spec in dict(data["categories"]).items():
            try:
                values = dict(spec)
                categories[name] = CategorySpec(
                    duration=float(values.get("duration", 3.0)),
                    report_every=float(values.get("report_every", 1.0)),
                    fail_on=tuple(str(place) for place in values.get("fail_on", ())),
                    needs_place=bool(values.get("needs_place", name == "go_to_place")),
                )
            except (TypeError, ValueError, OverflowError) as exc:  # OverflowError: float(10**400)
                raise ServeError(f"{source}: categories.{name}: {exc}") from None
            if not 0 < categories[name].duration < 1e6 or not 0 < categories[name].report_every < 1e6:
                raise ServeError(
                    f"{source}: categories.{name}: duration and report_every are positive seconds"
                )
    robots = data.get("robots", ["tinyRobot1"])
    if not isinstance(robots, list) or not all(isinstance(robot, str) for robot in robots):
        raise ServeError(f"{source}: robots: expected a list of names")
    return ServeConfig(
        fleet=str(data.get("fleet", "tinyRobot")),
        robots=tuple(robots),
        categories=categories,
        compatibility=str(data.get("compatibility", "standard")),
        rebegin=float(data.get("rebegin", 2.0)),
    )
