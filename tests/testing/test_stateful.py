"""The stateful kit of dynevent.testing: it finds nothing wrong in dynevent, and it catches a server broken.

The kit (:mod:`dynevent.testing.stateful`) is tested by use: it drives dynevent's machine in both
compatibility modes and through the conformance driver protocol and finds nothing, its observer follows
dynevent over random input sequences, and it catches each of a handful of deliberately broken servers,
several of which copy a defect of rmf_ros2.  (The machine's own invariants, which look inside dynevent,
are tests/spec/test_19_invariants.py's.)
"""

from __future__ import annotations

from collections.abc import Sequence

import attrs
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis.stateful import run_state_machine_as_test

from dynevent.conformance.vectors import InProcessImplementation
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import QueuedGoal, State
from dynevent.testing import (
    DyneventServer,
    ImplementationServer,
    Observer,
    ProtocolViolation,
    ServerStateMachine,
    ServerUnderTest,
    server_state_machine,
)
from dynevent.wire.messages import DynamicEventStatus
from dynevent.wire.vocab import DynamicState
from support.kit_runs import CONFIGS, RMF_ROS2_CONFIG, SEQUENCES, STEPS

# --------------------------------------------------------------------------- the kit on dynevent


class DyneventKit(ServerStateMachine):
    """The kit driving dynevent's own machine in the standard configuration."""

    def make_server(self) -> ServerUnderTest:
        return DyneventServer()


TestDyneventKit = pytest.mark.spec("R19.1", "R19.2", "R19.3", "R19.4", "R19.5", "R19.7")(DyneventKit.TestCase)
TestDyneventKit.settings = settings(settings.default, stateful_step_count=STEPS)


@pytest.mark.spec("R19.1", "R19.2", "R19.3", "R19.4", "R19.5", "R19.7", "R17.1", "R17.3")
def test_kit_finds_nothing_wrong_in_rmf_ros2_mode() -> None:
    machine_class = server_state_machine(DyneventServer, config=RMF_ROS2_CONFIG, name="RmfRos2Kit")
    run_state_machine_as_test(machine_class, settings=settings(settings.default, stateful_step_count=STEPS))


@pytest.mark.spec("R19.1", "R19.5")
def test_kit_drives_an_implementation_through_the_driver_protocol() -> None:
    machine_class = server_state_machine(
        lambda: ImplementationServer(InProcessImplementation()), name="DriverKit"
    )
    run_state_machine_as_test(
        machine_class,
        settings=settings(settings.default, max_examples=min(settings.default.max_examples, 25)),
    )


# --------------------------------------------------------------------------- deliberately broken servers


class CancelFreesTheRobot(DyneventServer):
    """rmf_ros2: once a CANCEL starts, the robot counts as idle and takes a NEXT as the child winds down."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        state = self.state
        if isinstance(event, ins.GoalRequested) and state is not None and state.cancels:
            open_goals = {queued.goal_uuid for queued in state.queued} | set(state.cancels)
            idle = attrs.evolve(state, running=None, cancels=())
            decision = machine.accept(idle, event.goal, self.config)
            if isinstance(decision, outs.Accepted) and event.goal_uuid not in open_goals:
                queued = QueuedGoal(goal_uuid=event.goal_uuid, goal=event.goal)
                self.state = attrs.evolve(state, queued=(*state.queued, queued))
                return [outs.GoalAccepted(goal_uuid=event.goal_uuid)]
        return super().apply(event)


class StatusWhileTheSlotIsHeld(DyneventServer):
    """rmf_ros2: at a child's end the status is published while the finished goal still holds the slot."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        before = self.state
        outputs = list(super().apply(event))
        running = None if before is None else before.running
        if isinstance(event, ins.ChildFinished) and running is not None and running.started:
            assert before is not None
            stale = DynamicEventStatus(
                dynamic_event_seq=before.seq,
                dynamic_state=DynamicState.RUNNING,
                status=event.status,
                id=running.child_id,
                time=machine.status_message(before, event.now).time,
            )
            outputs = [
                outs.PublishStatus(message=stale) if isinstance(output, outs.PublishStatus) else output
                for output in outputs
            ]
        return outputs


class SeqNotRecheckedAtStart(DyneventServer):
    """rmf_ros2: a goal accepted for one run can start in the next (the seq is not checked again)."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        state = self.state
        if isinstance(event, ins.GoalStarted) and state is not None and state.active:
            queued = tuple(
                attrs.evolve(item, goal=attrs.evolve(item.goal, dynamic_event_seq=state.seq))
                if item.goal_uuid == event.goal_uuid
                else item
                for item in state.queued
            )
            self.state = attrs.evolve(state, queued=queued)
        return super().apply(event)


class StubbornPeriodNotClamped(DyneventServer):
    """A hold begins with the requested period even when it is below the minimum."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        before = self.state
        outputs = list(super().apply(event))
        if before is not None and before.running is not None:
            requested = before.running.goal.stubborn_period
            outputs = [
                attrs.evolve(output, period=requested) if isinstance(output, outs.StubbornBegin) else output
                for output in outputs
            ]
        return outputs


class ForgetsQueuedGoalsAtShutdown(DyneventServer):
    """Shutdown answers the running goal but forgets goals accepted and not yet started."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        before = self.state
        outputs = list(super().apply(event))
        if isinstance(event, ins.Shutdown) and before is not None:
            forgotten = {queued.goal_uuid for queued in before.queued}
            outputs = [output for output in outputs if getattr(output, "goal_uuid", None) not in forgotten]
        return outputs


class RaisesOnKill(DyneventServer):
    """Raises when the task is killed while a child runs."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        if isinstance(event, ins.TaskKill) and self.state is not None and self.state.running is not None:
            raise RuntimeError("kill while running")
        return super().apply(event)


BROKEN: dict[str, tuple[type[DyneventServer], str]] = {
    "cancel_frees_the_robot": (CancelFreesTheRobot, "R19.2"),
    "status_while_the_slot_is_held": (StatusWhileTheSlotIsHeld, "R19.5"),
    "seq_not_rechecked_at_start": (SeqNotRecheckedAtStart, "R5.2"),
    "stubborn_period_not_clamped": (StubbornPeriodNotClamped, "R19.4"),
    "forgets_queued_goals_at_shutdown": (ForgetsQueuedGoalsAtShutdown, "R19.1"),
    "raises_on_kill": (RaisesOnKill, "R19.7"),
}


@pytest.mark.spec("R19.1", "R19.2", "R19.4", "R19.5", "R19.7", "R5.2")
@pytest.mark.parametrize("name", sorted(BROKEN))
def test_kit_catches_a_broken_server(name: str) -> None:
    server_class, rule = BROKEN[name]
    machine_class = server_state_machine(server_class, name=f"Broken_{name}")
    with pytest.raises(ProtocolViolation) as caught:
        run_state_machine_as_test(
            machine_class,
            settings=settings(
                max_examples=2_000,
                stateful_step_count=50,
                deadline=None,
                database=None,
                derandomize=True,
                phases=[Phase.generate],
                report_multiple_bugs=False,
                suppress_health_check=list(HealthCheck),
            ),
        )
    assert caught.value.rule == rule, str(caught.value)


# --------------------------------------------------------------------------- the kit's observer


@pytest.mark.spec("R19.1", "R19.2", "R19.5")
@pytest.mark.parametrize("mode", sorted(CONFIGS))
@given(events=SEQUENCES)
def test_the_kit_observer_accepts_dynevent_on_random_sequences(mode: str, events: list[ins.Input]) -> None:
    config = CONFIGS[mode]
    observer = Observer("fleet", "robot", config)
    state = State.new("fleet", "robot")
    for event in [*events, ins.Shutdown(now=events[-1].now)]:
        transition = machine.step(state, event, config)
        observer.observe(event, transition.outputs)
        state = transition.state
        assert (observer.phase, observer.seq, observer.current_id) == (
            state.phase,
            state.seq,
            state.current_id,
        )
    observer.check_all_answered()
