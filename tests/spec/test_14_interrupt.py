"""§14. Interruption: the tests of the rules of docs/spec.md §14.

The section's conformance vectors are src/dynevent/conformance/vectors/14-interrupt.json.
"""

from __future__ import annotations

import attrs
import pytest

from dynevent.server import outputs as outs
from dynevent.server.machine import (
    ServerConfig,
    any_description,
)
from support.scenario import (
    INACTIVE,
    RUNNING,
    WAITING,
    deferred,
    feedback,
    finished_goal,
    next_goal,
    running,
    start_child,
    status,
    stubborn,
    u,
    waiting,
)

# --------------------------------------------------------------------------- R14.1


@pytest.mark.spec("R14.1")
def test_interrupt_with_a_started_child_is_handed_to_it() -> None:
    run = running(child_id=5)
    assert run.interrupt() == (outs.InterruptChild(id=5),)
    assert run.state.interrupted
    assert (run.phase, run.state.status) == (RUNNING, "underway")


# --------------------------------------------------------------------------- R14.2


@pytest.mark.spec("R14.2")
def test_interrupt_without_a_child_is_confirmed() -> None:
    run = waiting()
    assert run.interrupt() == (outs.InterruptConfirmed(),)
    assert run.state.interrupted
    assert run.phase is WAITING


@pytest.mark.spec("R14.2", "R6.3")
def test_a_next_starting_while_interrupted_is_deferred() -> None:
    run = waiting()
    run.interrupt()
    assert run.submit(u(1), next_goal(1, 5)) == (
        outs.ExecuteGoal(goal_uuid=u(1)),
        feedback(u(1), "queued", 5),
        status(1, RUNNING, "queued", 5),
    )


# --------------------------------------------------------------------------- R14.3


@pytest.mark.spec("R14.3")
def test_resume_without_a_child_clears_the_interruption() -> None:
    run = waiting()
    run.interrupt()
    assert run.resume() == ()
    assert not run.state.interrupted
    assert run.submit(u(1), next_goal(1, 5))[1] == start_child(5)


@pytest.mark.spec("R14.3", "R6.3", "R14.5")
def test_an_interruption_outlives_the_child_it_was_handed_to() -> None:
    run = running(child_id=5)
    run.interrupt()
    run.child_end("completed")
    assert run.state.interrupted
    assert run.submit(u(2), next_goal(1, 6))[1] == feedback(u(2), "queued", 6)
    assert run.resume()[0] == start_child(6)
    assert not run.state.interrupted


@pytest.mark.spec("R14.3")
def test_resume_after_the_run_ended_still_clears() -> None:
    run = waiting()
    run.interrupt()
    run.submit(u(1), finished_goal(1))
    assert run.phase is INACTIVE and run.state.interrupted
    assert run.resume() == ()
    assert not run.state.interrupted


# --------------------------------------------------------------------------- R14.4


@pytest.mark.spec("R14.4")
def test_resume_with_a_started_child() -> None:
    run = running(child_id=5)
    run.interrupt()
    assert run.resume() == (outs.ResumeChild(id=5),)
    assert not run.state.interrupted


# --------------------------------------------------------------------------- R14.5


@pytest.mark.spec("R14.5", "R6.4")
def test_resume_starts_a_deferred_child() -> None:
    run = deferred(child_id=5)
    assert run.resume() == (start_child(5), feedback(u(1), "underway", 5), status(1, RUNNING, "underway", 5))
    assert run.state.running is not None
    assert (run.state.running.started, run.state.running.child_status, run.state.status) == (
        True,
        "underway",
        "underway",
    )
    assert not run.state.interrupted


@pytest.mark.spec("R14.5", "R12.2")
def test_resume_repeats_neither_execute_nor_clamp_notice() -> None:
    run = waiting()
    run.interrupt()
    run.submit(u(1), next_goal(1, 5, stubborn=0.5))
    assert run.resume() == (start_child(5), feedback(u(1), "underway", 5), status(1, RUNNING, "underway", 5))
    assert run.state.log_seq == 1


@pytest.mark.spec("R14.5", "R12.5")
def test_resume_of_a_deferred_child_ends_stubbornness() -> None:
    run = stubborn(3.0, child_id=5)
    run.interrupt()
    run.submit(u(2), next_goal(1, 6))
    assert run.resume() == (
        outs.StubbornEnd(),
        start_child(6),
        feedback(u(2), "underway", 6),
        status(1, RUNNING, "underway", 6),
    )


@pytest.mark.spec("R14.5", "R19.7")
def test_a_deferred_child_whose_description_no_longer_parses_still_starts() -> None:
    # Unreachable through accept (R6.1 parsed it), but a state built by hand or
    # edited in a snapshot may hold one: the machine must not raise, and the
    # child starts with no parsed description.
    run = deferred(child_id=5)
    assert run.state.running is not None
    broken = attrs.evolve(run.state.running, goal=next_goal(1, 5, description="{"))
    run.evolve(running=broken)
    outputs = run.resume()
    assert outputs[0] == outs.StartChild(category="go_to_place", description="{", id=5, parsed=None)
    assert outputs[0].parsed is None


@pytest.mark.spec("R14.5")
def test_a_deferred_child_with_a_null_description_starts_with_none() -> None:
    run = waiting(config=ServerConfig(categories={"perform_action": any_description}))
    run.interrupt()
    run.submit(u(1), next_goal(1, 5, category="perform_action", description="null"))
    outputs = run.resume()
    assert outputs[0] == outs.StartChild(category="perform_action", description="null", id=5, parsed=None)
