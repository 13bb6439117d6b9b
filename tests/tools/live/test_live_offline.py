"""What a live command says when it starts with no network but loopback (tests/net shows why)."""

from __future__ import annotations

from pathlib import Path

import pytest

from dynevent.tools.live import OFFLINE, offline


def _interfaces(tmp_path: Path, **states: str) -> Path:
    for name, state in states.items():
        (tmp_path / name).mkdir()
        (tmp_path / name / "operstate").write_text(state + "\n", encoding="ascii")
    return tmp_path


@pytest.mark.parametrize(
    ("states", "said"),
    [
        ({"lo": "unknown", "eth0": "down"}, True),
        ({"lo": "unknown"}, True),
        ({"lo": "unknown", "eth0": "down", "wlan0": "up"}, False),
        ({"lo": "unknown", "tun0": "unknown"}, False),  # a link without carrier sense is up
        ({"lo": "unknown", "eth0": "lowerlayerdown", "docker0": "dormant"}, True),
    ],
)
def test_a_command_started_offline_says_it_will_not_reach_other_hosts(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, states: dict[str, str], said: bool
) -> None:
    monkeypatch.delenv("ROS_AUTOMATIC_DISCOVERY_RANGE", raising=False)
    lines: list[str] = []
    assert offline(lines.append, _interfaces(tmp_path, **states)) is said
    assert lines == ([OFFLINE] if said else [])


def test_nothing_is_said_where_dds_stays_on_the_host_or_the_interfaces_cannot_be_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    lines: list[str] = []
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "localhost")
    assert not offline(lines.append, _interfaces(tmp_path, lo="unknown", eth0="down"))
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "SUBNET")
    assert not offline(lines.append, tmp_path / "no such folder")
    assert lines == []
