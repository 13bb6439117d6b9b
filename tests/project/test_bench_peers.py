"""The benchmark's peers are honest: each gives exactly dynevent's outputs, whole, on the scripted
workloads, and refuses the inputs dynevent refuses.

The tuple peer needs nothing but the standard library and is always checked;
the ``transitions`` and ``python-statemachine`` peers are checked when the
``bench`` extra is installed.  No timing here: speed is measured by bench/run.py.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from typing import Any

import attrs
import pytest

from dynevent.errors import DyneventError
from dynevent.server import outputs as outs
from dynevent.wire.messages import Feedback, LogEntry

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

script = importlib.import_module("bench.peers.script")
tuples = importlib.import_module("bench.peers.tuples")

PEERS = {
    "tuples": ("bench.peers.tuples", "TupleServer", None),
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
        output[2][1]
        for outputs in _reference(script.shared_script())
        for output in outputs
        if output[0] == "goal_rejected"
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
    assert {
        "stubborn_clamped",
        "log",
        "stubborn_begin",
        "stubborn_end",
        "cancel_child",
        "dynamic_event_finished",
        "ignored",
    } <= kinds


def test_the_whole_event_has_a_stubborn_child_and_a_cancelled_one() -> None:
    outputs = [output for step in _reference(script.whole_event()) for output in step]
    assert sum(output[0] == "start_child" for output in outputs) == 100
    assert sum(output[0] == "stubborn_clamped" for output in outputs) == 1
    assert sum(output[0] == "stubborn_begin" for output in outputs) == 1
    assert sum(output[0] == "stubborn_end" for output in outputs) == 1
    assert sum(output[0] == "cancel_child" for output in outputs) == 1
    assert outputs[-2] == ("dynamic_event_finished", "completed")


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


def _builtins_only(value: Any) -> bool:
    if isinstance(value, (tuple, list)):
        return all(_builtins_only(item) for item in value)
    if isinstance(value, dict):
        return all(_builtins_only(key) and _builtins_only(item) for key, item in value.items())
    return value is None or type(value) in (str, int, float, bool)


def test_the_tuple_peer_holds_and_gives_builtins_only() -> None:
    server = tuples.TupleServer("fleet", "robot", script.CATEGORIES)
    assert not hasattr(server, "__dict__")
    for outputs in script.play(server, script.shared_script()):
        assert _builtins_only(outputs)
        assert _builtins_only(server.data)


def test_plain_keeps_every_field_of_an_output_and_leaves_out_the_rule() -> None:
    feedback = Feedback(
        status="underway", id=11, logs=(LogEntry(seq=3, tier="info", unix_millis_time=9, text="x"),)
    )
    output = outs.PublishFeedback(goal_uuid=script.uuid(1), feedback=feedback, rule="R7.1")
    assert script.plain(output) == (
        "publish_feedback",
        script.uuid(1),
        ("Feedback", "underway", 11, (("LogEntry", 3, "info", 9, "x"),)),
    )
    assert script.plain(attrs.evolve(output, rule="R6.4")) == script.plain(output)
    other = attrs.evolve(output, feedback=attrs.evolve(feedback, logs=()))
    assert script.plain(other) != script.plain(output)


# Bad raw events: dynevent's input classes refuse each one, and so must every peer.
_GOOD_GOAL = (1, 1, "go_to_place", script.DESCRIPTION, 11, 0.0)
_BAD_EVENTS = [
    ("begin", -1, script.EVENT_DESCRIPTION),
    ("begin", 2**64, script.EVENT_DESCRIPTION),
    ("begin", 10, "{not json"),
    ("begin", 10, "[]"),
    ("begin", 10, '{"category": 1}'),
    ("begin", 10, '{"category": "a", "category": "b"}'),
    ("begin", 10, '{"detail": 3}'),
    ("request", "xyz", _GOOD_GOAL),
    ("request", script.uuid(1)[:31], _GOOD_GOAL),
    ("request", script.uuid(1), (-1, 1, "go_to_place", script.DESCRIPTION, 11, 0.0)),
    ("request", script.uuid(1), (2**32, 1, "go_to_place", script.DESCRIPTION, 11, 0.0)),
    ("request", script.uuid(1), (True, 1, "go_to_place", script.DESCRIPTION, 11, 0.0)),
    ("request", script.uuid(1), (1, 2**32, "go_to_place", script.DESCRIPTION, 11, 0.0)),
    ("request", script.uuid(1), (1, 1, "go\x00to", script.DESCRIPTION, 11, 0.0)),
    ("request", script.uuid(1), (1, 1, 7, script.DESCRIPTION, 11, 0.0)),
    ("request", script.uuid(1), (1, 1, "go_to_place", "\ud800", 11, 0.0)),
    ("request", script.uuid(1), (1, 1, "go_to_place", script.DESCRIPTION, -1, 0.0)),
    ("request", script.uuid(1), (1, 1, "go_to_place", script.DESCRIPTION, 2**64, 0.0)),
    ("request", script.uuid(1), (1, 1, "go_to_place", script.DESCRIPTION, 11, "soon")),
    ("request", script.uuid(1), (1, 1, "go_to_place", script.DESCRIPTION, 11, 1e39)),
    ("start", "not a uuid"),
    ("progress", "walking", "text", "info"),
    ("progress", "underway", "text", "loud"),
    ("progress", "underway", "x" * 16_385, "info"),
    ("progress", "underway", "a\x00b", "info"),
    ("progress", "underway", 5, "info"),
    ("finished", "done"),
]


@pytest.mark.parametrize("name", list(PEERS))
@pytest.mark.parametrize("event", _BAD_EVENTS, ids=repr)
def test_peer_refuses_the_inputs_dynevent_refuses(name: str, event: tuple[Any, ...]) -> None:
    prefix = [("begin", 10, script.EVENT_DESCRIPTION), *script.child_cycle(1, 11, script.uuid(1))[:2]]
    peer = _peer_class(name)("fleet", "robot", script.CATEGORIES)
    driver = script.DyneventDriver()
    script.play(peer, prefix)
    script.play(driver, prefix)
    with pytest.raises(DyneventError):
        script.play(driver, [event], 100)
    before = peer.data
    with pytest.raises(ValueError):
        script.play(peer, [event], 100)
    assert peer.data == before
    for late in (("begin", 10, script.EVENT_DESCRIPTION), ("request", script.uuid(1), _GOOD_GOAL)):
        kind, *values = late
        with pytest.raises(ValueError):
            getattr(peer, kind)(*values, 2**63)  # now beyond builtin_interfaces/Time


@pytest.mark.parametrize("name", list(PEERS))
@pytest.mark.parametrize(
    "damage",
    [
        lambda data: data.update(seq=-1),
        lambda data: data.update(status="walking"),
        lambda data: data.update(cancels=["x" * 32]),
        lambda data: data.update(description="{"),
        lambda data: data.pop("log_seq"),
        lambda data: data.update(phase="flying"),
    ],
)
def test_peer_restore_refuses_a_damaged_snapshot(name: str, damage: Any) -> None:
    cls = _peer_class(name)
    peer = cls("fleet", "robot", script.CATEGORIES)
    script.play(peer, script.shared_script()[:16])
    data = peer.snapshot()
    data.setdefault("phase", "waiting")
    damage(data)
    if name == "tuples" and "phase" in data and data["phase"] == "flying":
        data.pop("phase")
        data["active"] = "yes"
    with pytest.raises(ValueError):
        cls.restore(data, script.CATEGORIES)


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


def test_the_description_checks_beside_dynevent_give_its_verdicts() -> None:
    """bench/descriptions.py times jsonschema and fastjsonschema only where each gives dynevent's
    verdict on every description (its ``honest``); no timing here."""
    bench = importlib.import_module("bench.descriptions")
    checks = bench.available()
    assert {"dynevent", "jsonschema", "fastjsonschema"} <= set(checks)
    bench.honest(checks)
    lying = dict(checks, jsonschema=lambda category, description: True)
    with pytest.raises(AssertionError):
        bench.honest(lying)
