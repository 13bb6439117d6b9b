"""§12. Stubbornness: the tests of the rules of docs/spec.md §12.

The section's conformance vectors are src/dynevent/conformance/vectors/12-stubborn.json.

Stubbornness (begin, clamp, refresh ticks, re-anchoring, end).
"""

from __future__ import annotations

import attrs
import pytest

from dynevent.server import outputs as outs
from dynevent.server.machine import (
    Position,
    ServerConfig,
    Stubbornness,
)
from support.scenario import (
    CONFIG,
    SUCCEEDED,
    T0,
    WAITING,
    Run,
    answer,
    finished_goal,
    next_goal,
    running,
    s,
    status,
    stubborn,
    u,
    waiting,
)


def _hold(period: float, now: int, map_name: str, x: float, y: float) -> tuple[outs.StubbornHold]:
    return (outs.StubbornHold(period=period, since=now, map_name=map_name, x=x, y=y),)


def _delay(seconds: float) -> tuple[outs.StubbornDelay]:
    return (outs.StubbornDelay(delay=seconds),)


def _stubborn_at_origin(config: ServerConfig = CONFIG, period: float = 3.0) -> Run:
    """Stubborn since T0, anchored on L1 at (0, 0)."""
    run = running(child_id=5, stubborn=period, config=config)
    run.tick("L1", 0.0, 0.0)
    run.child_end("completed")
    assert run.state.stubborn is not None
    return run


# --------------------------------------------------------------------------- R12.1


@pytest.mark.spec("R12.1", "R8.4")
def test_stubbornness_begins_at_the_last_reported_position() -> None:
    run = running(child_id=5, stubborn=3.0)
    run.tick("L1", 9.0, 9.0, now=T0 - s(2))
    run.tick("L3", 1.5, -2.5, now=T0 - s(1))
    assert run.child_end("completed", now=T0) == (
        answer(u(1), SUCCEEDED, "", "completed", 5),
        outs.StubbornBegin(period=3.0, since=T0, map_name="L3", x=1.5, y=-2.5),
        status(1, WAITING, "standby", 5),
    )
    assert run.state.stubborn == Stubbornness(
        period=3.0, hold_since=T0, next_refresh=T0 + s(1), anchor=Position(map_name="L3", x=1.5, y=-2.5)
    )


@pytest.mark.spec("R12.1")
def test_stubbornness_without_a_reported_position() -> None:
    run = running(child_id=5, stubborn=3.0)
    assert run.child_end("completed")[1] == outs.StubbornBegin(
        period=3.0, since=T0, map_name=None, x=0.0, y=0.0
    )
    assert run.state.stubborn is not None
    assert run.state.stubborn.anchor is None


@pytest.mark.spec("R12.1", "R12.2")
@pytest.mark.parametrize(
    ("requested", "applied"), [(1e-45, 2.0), (0.5, 2.0), (2.0, 2.0), (2.5, 2.5), (600.0, 600.0)]
)
def test_the_applied_period_is_at_least_the_minimum(requested: float, applied: float) -> None:
    run = running(child_id=5, stubborn=requested)
    assert run.child_end("completed")[1] == outs.StubbornBegin(
        period=applied, since=T0, map_name=None, x=0.0, y=0.0
    )


@pytest.mark.spec("R12.1")
def test_the_configured_minimum_applies() -> None:
    run = running(child_id=5, stubborn=3.0, config=attrs.evolve(CONFIG, stubborn_minimum=10.0))
    assert run.child_end("completed")[1] == outs.StubbornBegin(
        period=10.0, since=T0, map_name=None, x=0.0, y=0.0
    )


@pytest.mark.spec("R12.1")
@pytest.mark.parametrize("period", [0.0, -0.0, -1.0, -3.4e38])
def test_no_stubbornness_for_a_period_of_zero_or_less(period: float) -> None:
    run = running(child_id=5, stubborn=period)
    assert run.child_end("completed") == (
        answer(u(1), SUCCEEDED, "", "completed", 5),
        status(1, WAITING, "standby", 5),
    )
    assert run.state.stubborn is None


@pytest.mark.spec("R12.1", "R8.4")
@pytest.mark.parametrize("final", ["failed", "canceled", "error"])
def test_stubbornness_begins_whatever_the_childs_final_status(final: str) -> None:
    run = running(child_id=5, stubborn=3.0)
    assert isinstance(run.child_end(final)[1], outs.StubbornBegin)


# --------------------------------------------------------------------------- R12.3


@pytest.mark.spec("R12.3")
def test_a_tick_outside_stubbornness_records_the_position_only() -> None:
    run = running(child_id=5)
    assert run.tick("L2", 4.0, 5.0) == ()
    assert run.state == attrs.evolve(run.before, position=Position(map_name="L2", x=4.0, y=5.0))


@pytest.mark.spec("R12.3", "R12.4")
def test_refresh_instants_fall_every_period_after_the_hold_began() -> None:
    run = _stubborn_at_origin()
    assert run.tick(now=T0 + s(0.5)) == ()
    assert run.tick(now=T0 + s(0.999999999)) == ()
    assert run.tick(now=T0 + s(1)) == _delay(1.0)
    assert run.tick(now=T0 + s(1.5)) == ()
    assert run.tick(now=T0 + s(1.999)) == ()
    assert run.tick(now=T0 + s(2.25)) == _delay(2.25)
    assert run.tick(now=T0 + s(2.9)) == ()
    assert run.tick(now=T0 + s(3)) == _delay(3.0)


@pytest.mark.spec("R12.3")
def test_missed_instants_are_not_replayed() -> None:
    run = _stubborn_at_origin()
    assert run.tick(now=T0 + s(4.5)) == _delay(4.5)
    assert run.tick(now=T0 + s(4.9)) == ()
    assert run.tick(now=T0 + s(5)) == _delay(5.0)


@pytest.mark.spec("R12.3")
def test_the_configured_refresh_period_applies() -> None:
    run = _stubborn_at_origin(attrs.evolve(CONFIG, stubborn_refresh=0.25))
    assert run.tick(now=T0 + s(0.2)) == ()
    assert run.tick(now=T0 + s(0.25)) == _delay(0.25)
    assert run.tick(now=T0 + s(0.4)) == ()
    assert run.tick(now=T0 + s(0.5)) == _delay(0.5)


@pytest.mark.spec("R12.3")
def test_ticks_between_instants_still_record_the_position() -> None:
    run = _stubborn_at_origin()
    assert run.tick("L1", 5.0, 5.0, now=T0 + s(0.5)) == ()
    assert run.state.position == Position(map_name="L1", x=5.0, y=5.0)
    # the anchor only moves at a refresh
    assert run.state.stubborn is not None
    assert run.state.stubborn.anchor == Position(map_name="L1", x=0.0, y=0.0)


# --------------------------------------------------------------------------- R12.4


@pytest.mark.spec("R12.4")
def test_a_robot_that_moved_re_anchors_and_the_hold_restarts() -> None:
    run = _stubborn_at_origin()
    assert run.tick("L1", 0.5, 0.0, now=T0 + s(1)) == _hold(3.0, T0 + s(1), "L1", 0.5, 0.0)
    assert run.state.stubborn == Stubbornness(
        period=3.0, hold_since=T0 + s(1), next_refresh=T0 + s(2), anchor=Position(map_name="L1", x=0.5, y=0.0)
    )
    # still at the new anchor: the delay counts from the restart
    assert run.tick("L1", 0.5, 0.0, now=T0 + s(2)) == _delay(1.0)
    assert run.tick("L1", 0.55, 0.0, now=T0 + s(3.5)) == _delay(2.5)


@pytest.mark.spec("R12.4")
def test_another_map_re_anchors() -> None:
    run = _stubborn_at_origin()
    assert run.tick("L2", 0.0, 0.0, now=T0 + s(1)) == _hold(3.0, T0 + s(1), "L2", 0.0, 0.0)


@pytest.mark.spec("R12.4", "R12.1")
def test_without_an_anchor_the_first_refresh_anchors() -> None:
    run = stubborn(3.0, position=False)
    assert run.tick("L1", 7.0, 8.0, now=T0 + s(0.5)) == ()
    assert run.tick("L1", 7.0, 8.0, now=T0 + s(1)) == _hold(3.0, T0 + s(1), "L1", 7.0, 8.0)
    assert run.tick("L1", 7.0, 8.0, now=T0 + s(2)) == _delay(1.0)


@pytest.mark.spec("R12.4")
def test_the_move_threshold_is_a_euclidean_distance_and_strict() -> None:
    run = _stubborn_at_origin()
    assert run.tick("L1", 0.1, 0.0, now=T0 + s(1)) == _delay(1.0)  # exactly 0.1 m: not farther
    assert run.tick("L1", 0.0, -0.1, now=T0 + s(2)) == _delay(2.0)
    assert run.tick("L1", 0.08, 0.08, now=T0 + s(3)) == _hold(3.0, T0 + s(3), "L1", 0.08, 0.08)  # 0.113 m
    run = _stubborn_at_origin(attrs.evolve(CONFIG, stubborn_move_threshold=0.45))
    assert run.tick("L1", 0.3, 0.4, now=T0 + s(1)) == _hold(3.0, T0 + s(1), "L1", 0.3, 0.4)  # 0.5 m


@pytest.mark.spec("R12.4")
def test_the_move_threshold_is_never_below_a_centimetre() -> None:
    run = _stubborn_at_origin(attrs.evolve(CONFIG, stubborn_move_threshold=0.001))
    assert run.tick("L1", 0.005, 0.0, now=T0 + s(1)) == _delay(1.0)
    assert run.tick("L1", 0.02, 0.0, now=T0 + s(2)) == _hold(3.0, T0 + s(2), "L1", 0.02, 0.0)


@pytest.mark.spec("R12.3", "R12.4")
def test_refresh_cadence_is_kept_across_a_re_anchor() -> None:
    run = _stubborn_at_origin()
    assert run.tick("L1", 0.0, 0.0, now=T0 + s(1)) == _delay(1.0)
    assert run.tick("L1", 0.0, 0.0, now=T0 + s(1.2)) == ()
    # the refresh due at T0 + 2 s comes late, at T0 + 2.5 s, and re-anchors: the hold restarts then
    assert run.tick("L1", 1.0, 0.0, now=T0 + s(2.5)) == _hold(3.0, T0 + s(2.5), "L1", 1.0, 0.0)
    # the cadence stays the one stubbornness began with: the next instant is T0 + 3 s
    assert run.tick("L1", 1.0, 0.0, now=T0 + s(3)) == _delay(0.5)
    assert run.tick("L1", 1.0, 0.0, now=T0 + s(3.5)) == ()


# --------------------------------------------------------------------------- R12.5


@pytest.mark.spec("R12.5", "R6.4", "R14.5", "R11.1", "R13.1", "R15.2")
@pytest.mark.parametrize("ender", ["next", "resume", "finished", "task_cancel", "task_kill", "shutdown"])
def test_every_way_stubbornness_ends(ender: str) -> None:
    run = stubborn(3.0, child_id=5)
    if ender == "next":
        outputs = run.submit(u(2), next_goal(1, 6))
    elif ender == "resume":
        run.interrupt()
        run.submit(u(2), next_goal(1, 6))
        assert run.state.stubborn is not None
        outputs = run.resume()
    elif ender == "finished":
        outputs = run.submit(u(2), finished_goal(1))
    elif ender == "task_cancel":
        outputs = run.task_cancel()
    elif ender == "task_kill":
        outputs = run.task_kill()
    else:
        outputs = run.shutdown()
    assert outputs.count(outs.StubbornEnd()) == 1
    assert run.state.stubborn is None
    # no refresh afterwards
    assert run.tick(now=T0 + s(5)) == ()


@pytest.mark.spec("R12.5", "R12.3")
def test_stubbornness_outlives_ticks_and_queries() -> None:
    run = stubborn(3.0)
    run.query()
    run.interrupt()
    run.resume()
    assert run.state.stubborn is not None
    assert run.tick("L1", 1.0, 2.0, now=T0 + s(1)) == _delay(1.0)


# --------------------------------------------------------------------------- R12.2


@pytest.mark.spec("R12.2")
def test_clamp_text_uses_the_configured_minimum() -> None:
    run = waiting(config=attrs.evolve(CONFIG, stubborn_minimum=2.5))
    outputs = run.submit(u(1), next_goal(1, 5, stubborn=1.25))
    log = outputs[2]
    assert isinstance(log, outs.Log)
    assert log.entry.text == "stubborn_period 1.25 s is below the minimum of 2.5 s; 2.5 s will be used"
