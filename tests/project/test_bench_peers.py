"""The benchmark's peers are honest: each decides exactly as dynevent does on the scripted workloads.

The floor peer needs nothing but the standard library and is always checked;
the ``transitions`` and ``python-statemachine`` peers are checked when the
``bench`` extra is installed.  No timing here: speed is measured by bench/run.py.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

script = importlib.import_module("bench.peers.script")
floor = importlib.import_module("bench.peers.floor")

PEERS = {
    "floor": ("bench.peers.floor", "FloorServer", None),
    "transitions": ("bench.peers.with_transitions", "TransitionsServer", "transitions"),
    "statemachine": ("bench.peers.with_statemachine", "StatemachineServer", "statemachine"),
}


def _peer_class(name: str) -> Any:
    module, cls, library = PEERS[name]
    if library is not None:
        pytest.importorskip(library)
    return getattr(importlib.import_module(module), cls)


def _reference(events: list[Any]) -> list[Any]:
    driver = script.DyneventDriver()
    return [driver.common(outputs) for outputs in script.play(driver, events)]


SCRIPTS = {
    "shared": script.shared_script,
    "child_cycle": lambda: [
        ("begin", 10, script.EVENT_DESCRIPTION),
        *script.child_cycle(1, 11, script.uuid(1)),
    ],
    "whole_event": lambda: script.whole_event(children=20),
}


@pytest.mark.parametrize("name", list(PEERS))
@pytest.mark.parametrize("workload", list(SCRIPTS))
def test_peer_gives_dynevent_s_outputs(name: str, workload: str) -> None:
    events = SCRIPTS[workload]()
    peer = _peer_class(name)("fleet", "robot", script.CATEGORIES)
    got = script.play(peer, events)
    expected = _reference(events)
    for index, (mine, theirs) in enumerate(zip(got, expected, strict=True)):
        assert mine == theirs, f"event {index}: {events[index]}"


@pytest.mark.parametrize("name", list(PEERS))
def test_peer_accept_decides_as_dynevent_at_every_step(name: str) -> None:
    """``accept`` is a pure query: ask it about every goal of the script, in every state the script visits."""
    events = script.shared_script()
    goals = [event[2] for event in events if event[0] == "request"]
    peer = _peer_class(name)("fleet", "robot", script.CATEGORIES)
    driver = script.DyneventDriver()
    for index, event in enumerate(events):
        for goal in goals:
            assert peer.accept(goal) == driver.accept(goal), f"after event {index - 1}, goal {goal}"
        script.play(peer, [event], index)
        script.play(driver, [event], index)


def test_the_shared_script_meets_every_refusal_the_peers_implement() -> None:
    reasons = {
        output[2]
        for outputs in _reference(script.shared_script())
        for output in outputs
        if output[0] == "rejected"
    }
    assert reasons == {
        "seq_mismatch",
        "inactive",
        "uninitialized_event_type",
        "unknown_event_type",
        "busy",
        "unsupported_category",
        "description_not_json",
        "non_finite_stubborn_period",
        "stale_id",
        "cancel_idle",
        "cancel_id_mismatch",
    }
    kinds = {output[0] for outputs in _reference(script.shared_script()) for output in outputs}
    assert {"clamped", "stubborn_begin", "stubborn_end", "cancel_child", "finished", "ignored"} <= kinds


def test_the_whole_event_has_a_stubborn_child_and_a_cancelled_one() -> None:
    outputs = [output for step in _reference(script.whole_event()) for output in step]
    assert sum(output[0] == "start_child" for output in outputs) == 100
    assert sum(output[0] == "clamped" for output in outputs) == 1
    assert sum(output[0] == "stubborn_begin" for output in outputs) == 1
    assert sum(output[0] == "stubborn_end" for output in outputs) == 1
    assert sum(output[0] == "cancel_child" for output in outputs) == 1
    assert outputs[-2] == ("finished", "completed")


@pytest.mark.parametrize("name", list(PEERS))
def test_peer_snapshots_round_trip(name: str) -> None:
    cls = _peer_class(name)
    events = script.shared_script()
    for cut in (3, 15, 30, 33, len(events)):
        peer = cls("fleet", "robot", script.CATEGORIES)
        script.play(peer, events[:cut])
        restored = cls.loads(peer.dumps(), script.CATEGORIES)
        assert restored.dump() == peer.dump()
        assert script.play(restored, events[cut:], cut) == script.play(peer, events[cut:], cut)


def test_the_floor_is_plain() -> None:
    server = floor.FloorServer("fleet", "robot", script.CATEGORIES)
    assert not hasattr(server, "__dict__")


def test_results_sections_are_replaced_in_place_and_kept_by_a_rewrite(tmp_path: Path) -> None:
    results = importlib.import_module("bench.results")
    path = tmp_path / "results.md"
    path.write_text("# tables\n", encoding="utf-8")
    results.write_section("ros-fleet", ["## fleet", "first"], path)
    results.write_section("ros-roundtrip", ["## trip", "one"], path)
    results.write_section("ros-fleet", ["## fleet", "second"], path)
    text = path.read_text(encoding="utf-8")
    assert "first" not in text and text.index("second") < text.index("one")
    rewritten = results.keep_sections("# new tables\n", path)
    assert rewritten.startswith("# new tables\n")
    assert results.sections(rewritten) == results.sections(text)
