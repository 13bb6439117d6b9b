"""The tests across hosts: network namespaces as hosts on one bridge (hosts.py), with the network's
faults, and ROS 2 sites on them (sites.py).

They need root, ``ip netns`` and ``nft`` (Debian's ``nftables``); the ROS tests among them need ROS 2
too (``. build/ros/env.sh``).  Elsewhere they are skipped with a one-line reason, except under
``CI=true``, where the run fails instead: CI installs what they need and must run them.
"""

from __future__ import annotations

import faulthandler
import itertools
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ros"))
from hosts import Site, missing
from ros_support import ROS, WHY
from sites import RosSite

MISSING = missing()
collect_ignore_glob = [] if ROS else ["test_ros_*.py"]

#: The longest any test across hosts may take, in seconds: a backstop above every bounded wait of a
#: test (the longest partition is 120 s, and its answer is waited for after the heal).
TEST_DEADLINE = 600


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    here = Path(__file__).resolve().parent
    ours = [item for item in items if here in Path(str(item.fspath)).resolve().parents]
    why = MISSING or (None if ROS else WHY)
    if os.environ.get("CI") == "true" and (MISSING is not None or not ROS):
        raise pytest.UsageError(f"CI=true and the tests across hosts cannot run: {why}")
    if MISSING is not None:
        skip = pytest.mark.skip(reason=MISSING)
        for item in ours:
            item.add_marker(skip)


@pytest.fixture(autouse=True)
def _deadline() -> Iterator[None]:
    faulthandler.dump_traceback_later(TEST_DEADLINE, exit=True)
    yield
    faulthandler.cancel_dump_traceback_later()


@pytest.fixture
def site() -> Iterator[Callable[[Sequence[str]], Site]]:
    """Make a site of hosts by their names; every site made is removed after the test."""
    made: list[Site] = []

    def make(names: Sequence[str]) -> Site:
        made.append(Site(names))
        return made[-1]

    yield make
    for each in made:
        each.close()


@pytest.fixture
def ros_site(tmp_path: Path) -> Iterator[Callable[..., RosSite]]:
    """Make a ROS 2 site (:class:`sites.RosSite`): hosts by their names, DDS discovery in a mode of
    :data:`sites.MODES`; removed after the test."""
    made: list[RosSite] = []
    numbers = itertools.count()  # a folder each, whichever thread makes the site

    def make(names: Sequence[str], mode: str = "multicast") -> RosSite:
        site = RosSite(Site(names), mode, tmp_path / f"site{next(numbers)}")
        made.append(site)
        return site

    yield make
    for each in made:
        each.close()
