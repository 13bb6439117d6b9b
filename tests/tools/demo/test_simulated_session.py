"""The simulated session, end-to-end outcomes, and the agreement of the client and server machines."""

from __future__ import annotations

import json
import math
from typing import Any

import attrs
import pytest
from hypothesis import event, given
from hypothesis import strategies as st
from hypothesis.control import currently_in_test_context

from dynevent import client
from dynevent.client import SECOND, ClientState, Outcome, OutcomeKind, Refused, SendGoal
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.tools.demo.simulated_session import (
    Adapter,
    ChildScript,
    Options,
    SimulatedSession,
    format_timeline,
    timeline_jsonl,
)
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import Compatibility, DynamicState, EventType, IdPolicy, RejectReason, Status

PREFIX = "0123456789abcdef"
U32 = 2**32 - 1
U64 = 2**64 - 1
MS = 1_000_000  # a millisecond on the session's clock (instants are nanoseconds)
#: A millisecond as a duration: durations are seconds (dynevent.wire.units).
D_MS = 0.001
CATEGORIES = ("go_to_place", "perform_action")
CONFIG = machine.ServerConfig(categories=dict.fromkeys(CATEGORIES, machine.any_description))


def session(
    *,
    config: machine.ServerConfig = CONFIG,
    server: machine.State | None = None,
    scripts: tuple[ChildScript, ...] = (),
    **options: Any,
) -> SimulatedSession:
    seed = options.pop("seed", 0)
    return SimulatedSession(
        ClientState.new(PREFIX),
        server if server is not None else machine.State.new("tinyRobot", "tinyRobot1"),
        config,
        adapter=Adapter(scripts=scripts),
        options=Options(**options),
        seed=seed,
    )


def started(lb: SimulatedSession, event_id: int = 5) -> SimulatedSession:
    lb.begin('{"category": "patrol"}', event_id=event_id)
    lb.run()
    return lb


def view(state: ClientState | machine.State) -> tuple[DynamicState, int, int]:
    return (state.phase, state.seq, state.current_id)


def outcome_kinds(lb: SimulatedSession) -> list[tuple[int, OutcomeKind]]:
    return [(outcome.goal.event_type, outcome.kind) for outcome in lb.outcomes]


# --------------------------------------------------------------------------- wiring


def test_a_goal_is_requested_then_started_by_the_binding() -> None:
    lb = started(session())
    (send,) = lb.request_next("go_to_place", '"pantry"')
    assert isinstance(send, SendGoal)
    lb.run()
    kinds = [(item.direction, item.kind) for item in lb.timeline]
    requested = kinds.index(("client->server", "goal_requested"))
    # ROS answers the request, then calls handle_accepted: the response goes out before the start
    assert kinds[requested + 1 : requested + 4] == [
        ("server->client", "goal_response"),
        ("adapter", "goal_started"),
        ("adapter", "start_child"),
    ]
    assert outcome_kinds(lb) == [(EventType.NEXT, OutcomeKind.COMPLETED)]
    assert view(lb.client) == view(lb.server) == (DynamicState.WAITING, 1, 6)  # R2.2


def test_a_late_client_gets_the_transient_local_begin_and_status() -> None:
    server = machine.step(
        machine.State.new("f", "r"), ins.Begin(description='{"detail": "d"}', event_id=9, now=0), CONFIG
    ).state
    lb = session(server=server)
    lb.run()
    assert lb.client.description == '{"detail": "d"}'
    assert view(lb.client) == view(lb.server) == (DynamicState.WAITING, 1, 9)


def test_sessions_replay_exactly_from_their_seed() -> None:
    def play(seed: int) -> str:
        lb = started(
            session(seed=seed, delay=(0, 0.02), start_delay=(0, 0.02), reorder=True, drop_feedback=0.5)
        )
        lb.request_next("go_to_place", '"a"', timeout=1)
        lb.send_foreign(
            Goal(
                dynamic_event_seq=1,
                event_type=EventType.NEXT,
                category="go_to_place",
                description='"b"',
                id=50,
            )
        )
        lb.advance(300 * D_MS)
        lb.request_cancel()
        lb.run()
        lb.request_finish()
        lb.run()
        return lb.timeline_jsonl()

    assert play(3) == play(3)
    assert len({play(seed) for seed in range(6)}) > 1


def test_timeline_as_json_lines_and_text() -> None:
    lb = started(session(delay=(D_MS, 2 * D_MS)))
    lb.request_next("go_to_place", '"a"', stubborn_period=math.nan)
    lb.request_next("go_to_place", '"a"', stubborn_period=1.0)
    lb.run()
    lines = timeline_jsonl(lb.timeline).splitlines()
    records = [json.loads(line) for line in lines]
    assert len(records) == len(lb.timeline)
    assert {record["direction"] for record in records} == {
        "client",
        "client->server",
        "server->client",
        "adapter",
    }
    assert all(
        set(record) == {"time", "direction", "kind", "summary", "decision", "record"} for record in records
    )
    assert records[0]["record"]["type"] == "begin"
    refusal = next(record for record in records if record["decision"].startswith("refused"))
    assert refusal["record"]["rejection"]["reason"] == "non_finite_stubborn_period"
    assert [record["time"] for record in records] == sorted(record["time"] for record in records)
    text = format_timeline(lb.timeline)
    assert text == lb.format_timeline() and len(text.splitlines()) == len(lines)
    assert "goal_requested" in text and "-> accepted" in text
    assert format_timeline([]) == ""


def test_run_limit_and_pending() -> None:
    lb = session()
    lb.begin(event_id=1)
    assert [kind for _, kind in lb.pending()] == ["client", "client", "client"]
    assert not lb.quiescent and lb.statuses_in_flight
    with pytest.raises(RuntimeError, match="settle"):
        lb.run(limit=1)
    lb.run()
    assert lb.quiescent and not lb.statuses_in_flight and not lb.step()


def test_options_and_scripts_check_their_values() -> None:
    with pytest.raises(ValueError, match="low <= high"):
        Options(delay=(5, 1))
    with pytest.raises(ValueError, match=r"start_delay: expected a finite duration in seconds, 0 or more"):
        Options(start_delay=(-1, 1))
    with pytest.raises(ValueError, match=r"Options.delay: .* is this nanoseconds\?"):
        Options(delay=(1_000_000, 3_000_000))  # 1 to 3 ms, in nanoseconds: refused, not taken as days
    with pytest.raises(ValueError, match=r"SimulatedSession.advance.duration"):
        started(session()).advance(SECOND)
    with pytest.raises(ValueError, match="probability"):
        Options(drop_feedback=1.5)
    with pytest.raises(ValueError, match="task statuses"):
        ChildScript(final_status="done")
    with pytest.raises(ValueError, match="duration"):
        ChildScript(cancel_after=-1)
    with pytest.raises(ValueError, match=r"ChildScript.reports\[0\]: durations are in seconds"):
        ChildScript(reports=((60 * SECOND, "underway"),))  # nanoseconds, not seconds
    with pytest.raises(ValueError, match=r"ChildScript.cancel_after: durations are in seconds"):
        ChildScript(cancel_after=SECOND // 5)
    with pytest.raises(ValueError, match="ChildScript"):
        Adapter(scripts=[1])  # type: ignore[list-item]
    assert ChildScript(final_status=Status.FAILED).final_status == "failed"


def test_stubbornness_is_recorded_as_adapter_effects() -> None:
    lb = started(session(delay=(D_MS, D_MS)))
    lb.request_next("go_to_place", '"a"', stubborn_period=1.0)
    lb.run()
    lb.server_input(ins.Tick(now=lb.now + SECOND, map_name="L1"))
    lb.request_next("go_to_place", '"b"')
    lb.run()
    kinds = [item.kind for item in lb.timeline if item.direction == "adapter"]
    for kind in ("stubborn_clamped", "stubborn_begin", "tick", "stubborn_hold", "stubborn_end"):
        assert kind in kinds


def test_adapter_scripts_follow_the_order_children_start() -> None:
    adapter = Adapter(
        scripts=(ChildScript(final_status="failed"),), default=ChildScript(final_status="skipped")
    )
    assert adapter.script(0).final_status == "failed"
    assert adapter.script(5).final_status == "skipped"
    start = outs.StartChild(category="c", description="1", id=3, parsed=1)
    planned = adapter.react(start, now=10, index=0)
    assert [type(item).__name__ for _, item in planned] == ["ChildProgress", "ChildFinished"]
    assert planned[-1][0] == 10 + 2 * SECOND
    assert adapter.react(outs.InterruptChild(id=3), now=0, index=0) == ()


def test_stale_adapter_inputs_are_dropped_not_delivered() -> None:
    lb = started(session(scripts=(ChildScript(cancel_after=0),)))
    lb.request_next("go_to_place", '"a"')
    lb.advance(10 * D_MS)
    lb.request_cancel()
    lb.run()
    stale = [item for item in lb.timeline if item.decision.startswith("stale")]
    assert {item.kind for item in stale} == {"child_progress", "child_finished"}
    assert outcome_kinds(lb) == [
        (EventType.NEXT, OutcomeKind.CANCELED),
        (EventType.CANCEL, OutcomeKind.CANCELED),
    ]


# --------------------------------------------------------------------------- every outcome kind end to end


@pytest.mark.parametrize(
    ("final", "kind"),
    [
        ("completed", OutcomeKind.COMPLETED),
        ("failed", OutcomeKind.FAILED),
        ("error", OutcomeKind.ERROR),
        ("skipped", OutcomeKind.SKIPPED),
        ("canceled", OutcomeKind.CANCELED),
        ("blocked", OutcomeKind.ERROR),
    ],
)
def test_child_final_statuses(final: str, kind: OutcomeKind) -> None:
    lb = started(session(scripts=(ChildScript(final_status=final),)))
    lb.request_next("go_to_place", '"a"')
    lb.run()
    assert outcome_kinds(lb) == [(EventType.NEXT, kind)]


def test_canceled_by_our_cancel() -> None:
    lb = started(session(scripts=(ChildScript(finish_after=None),)))
    lb.request_next("go_to_place", '"a"')
    lb.advance(D_MS)
    lb.request_cancel()
    lb.run()
    assert outcome_kinds(lb) == [
        (EventType.NEXT, OutcomeKind.CANCELED),
        (EventType.CANCEL, OutcomeKind.CANCELED),
    ]
    assert view(lb.client) == view(lb.server) == (DynamicState.WAITING, 1, 6)


def test_killed_when_the_task_is_killed() -> None:
    lb = started(session(scripts=(ChildScript(finish_after=None, kill_after=D_MS),)))
    lb.request_next("go_to_place", '"a"')
    lb.advance(D_MS)
    lb.task_kill()
    lb.run()
    assert outcome_kinds(lb) == [(EventType.NEXT, OutcomeKind.KILLED)]
    assert view(lb.client) == view(lb.server) == (DynamicState.INACTIVE, 1, 0)


def test_timeout_cancels_and_reports_timeout() -> None:
    lb = started(session(scripts=(ChildScript(finish_after=None),), delay=(D_MS, 3 * D_MS)))
    lb.request_next("go_to_place", '"a"', timeout=1)
    lb.run()
    assert outcome_kinds(lb) == [
        (EventType.NEXT, OutcomeKind.TIMEOUT),
        (EventType.CANCEL, OutcomeKind.CANCELED),
    ]
    timed_out = next(item for item in lb.timeline if item.kind == "timed_out")
    assert timed_out.time >= SECOND


def test_timeout_of_a_deferred_child_with_all_feedback_lost() -> None:
    lb = started(session(drop_feedback=1.0))
    lb.interrupt()
    lb.request_next("go_to_place", '"a"', timeout=1)
    lb.run()
    assert any(item.decision == "dropped" for item in lb.timeline)
    assert outcome_kinds(lb) == [
        (EventType.NEXT, OutcomeKind.TIMEOUT),
        (EventType.CANCEL, OutcomeKind.CANCELED),
    ]
    assert view(lb.client) == view(lb.server) == (DynamicState.WAITING, 1, 6)


def test_execution_failure_race_with_another_client() -> None:
    kinds = set()
    for seed in range(12):
        lb = started(session(seed=seed, start_delay=(0, 10 * D_MS), reorder=True))
        lb.request_next("go_to_place", '"a"')
        foreign = Goal(
            dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place", description='"b"', id=100
        )
        lb.send_foreign(foreign)
        lb.run()
        (outcome,) = lb.outcomes
        kinds.add(outcome.kind)
        if outcome.kind is OutcomeKind.EXECUTION_FAILURE:
            assert (outcome.reason, outcome.execution_failure) == (RejectReason.RACE, "race condition")
            assert any(item.decision == "aborted: race condition" for item in lb.timeline)
    assert kinds == {OutcomeKind.COMPLETED, OutcomeKind.EXECUTION_FAILURE}


@pytest.mark.parametrize("ros", [False, True])
def test_rejected_when_the_view_is_behind(ros: bool) -> None:
    lb = started(session(delay=(10 * D_MS, 10 * D_MS), ros_rejections=ros))
    lb.send_foreign(
        Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place", description='"b"', id=6)
    )
    lb.advance(15 * D_MS)  # the foreign child runs; its status is still on its way
    assert lb.client.phase is DynamicState.WAITING and lb.server.phase is DynamicState.RUNNING
    lb.request_next("go_to_place", '"a"')
    lb.run()
    (outcome,) = lb.outcomes
    assert outcome.kind is OutcomeKind.REJECTED
    assert outcome.reason is (None if ros else RejectReason.BUSY)


def test_superseded_when_a_new_run_began_before_the_goal_started() -> None:
    lb = started(session(start_delay=(1, 1)))
    lb.request_next("go_to_place", '"a"')
    lb.advance(10 * D_MS)
    lb.task_cancel()
    lb.begin(event_id=20)
    lb.run()
    (outcome,) = lb.outcomes
    assert (outcome.kind, outcome.reason) == (OutcomeKind.SUPERSEDED, RejectReason.RACE)
    assert view(lb.client) == view(lb.server) == (DynamicState.WAITING, 2, 20)


def test_superseded_when_the_request_arrives_in_the_next_run() -> None:
    lb = started(session(delay=(5 * D_MS, 5 * D_MS)))
    lb.request_next("go_to_place", '"a"')
    lb.task_cancel()
    lb.begin(event_id=20)  # both runs change before the request arrives
    lb.run()
    (outcome,) = lb.outcomes
    assert (outcome.kind, outcome.reason) == (OutcomeKind.SUPERSEDED, RejectReason.SEQ_MISMATCH)


def test_shutdown_answers_with_execution_failure() -> None:
    lb = started(session(scripts=(ChildScript(finish_after=None),)))
    lb.request_next("go_to_place", '"a"')
    lb.advance(D_MS)
    lb.shutdown()
    lb.run()
    (outcome,) = lb.outcomes
    assert (outcome.kind, outcome.reason) == (OutcomeKind.EXECUTION_FAILURE, RejectReason.SHUTTING_DOWN)
    assert view(lb.client) == view(lb.server) == (DynamicState.INACTIVE, 1, 0)


def test_seq_wrap_is_followed() -> None:
    lb = session(server=attrs.evolve(machine.State.new("f", "r"), seq=U32))
    started(lb, event_id=3)
    assert view(lb.client) == view(lb.server) == (DynamicState.WAITING, 0, 3)
    assert any(item.kind == "seq_wrapped" for item in lb.timeline)
    lb.request_finish()
    lb.run()
    assert outcome_kinds(lb) == [(EventType.FINISHED, OutcomeKind.COMPLETED)]


def test_next_right_after_an_outcome_is_accepted() -> None:
    lb = started(session(delay=(D_MS, 5 * D_MS), seed=4))
    outcomes_seen = 0
    lb.request_next("go_to_place", '"a"')
    while lb.step():
        if len(lb.outcomes) > outcomes_seen and len(lb.outcomes) < 4:
            outcomes_seen = len(lb.outcomes)
            (send,) = lb.request_next("go_to_place", '"b"')
            assert isinstance(send, SendGoal)
    assert [outcome.kind for outcome in lb.outcomes] == [OutcomeKind.COMPLETED] * 4


# --------------------------------------------------------------------------- the agreement property

WAIT = st.tuples(st.just("wait"), st.integers(0, 3 * SECOND))
NEXT = st.tuples(
    st.just("next"),
    st.sampled_from((*CATEGORIES, *CATEGORIES, "teleport")),
    st.sampled_from(('"pantry"', '{"place": "L1"}', '"lobby"', "[1,")),
    st.sampled_from((0.0, 0.0, 1.0, 3.0, math.nan)),
    st.sampled_from((None, None, 0.25, 1, 5)),  # seconds
)
BEGIN = st.tuples(st.just("begin"), st.sampled_from((0, 5, 1000, U64 - 1, U64)))
# one_of draws its branches evenly: repeating a branch weighs it
ACTIONS = st.one_of(
    NEXT,
    NEXT,
    NEXT,
    WAIT,
    WAIT,
    WAIT,
    st.just(("settle",)),
    st.just(("settle",)),
    BEGIN,
    st.sampled_from((("cancel",), ("cancel",), ("finish",), ("next_plain",), ("next_plain",))),
    st.sampled_from(
        (
            ("task_cancel",),
            ("task_kill",),
            ("interrupt",),
            ("resume",),
            ("foreign_next",),
            ("foreign_cancel",),
        )
    ),
)


def SECONDS(most: float) -> st.SearchStrategy[float]:
    """Durations from 0 to ``most`` seconds, in whole nanoseconds."""
    return st.integers(0, round(most * SECOND)).map(lambda nanoseconds: nanoseconds / SECOND)


SCRIPTS = st.builds(
    ChildScript,
    reports=st.lists(st.tuples(SECONDS(2), st.sampled_from(("underway", "delayed", "blocked"))), max_size=2),
    finish_after=st.one_of(st.none(), SECONDS(3)),
    final_status=st.sampled_from([status.value for status in Status]),
    cancel_after=SECONDS(1),
    kill_after=SECONDS(0.5),
)
OPTIONS = st.builds(
    Options,
    delay=st.sampled_from(((0, 0), (0, 5 * D_MS), (D_MS, 50 * D_MS))),
    start_delay=st.sampled_from(((0, 0), (0, 20 * D_MS))),
    reorder=st.booleans(),
    drop_feedback=st.sampled_from((0.0, 0.5, 1.0)),
    ros_rejections=st.booleans(),
)
CONFIGS = {
    "standard": CONFIG,
    "adapter_ids": attrs.evolve(CONFIG, id_policy=IdPolicy.ADAPTER),
    "rmf_ros2": machine.ServerConfig.rmf_ros2(dict.fromkeys(CATEGORIES, machine.any_description)),
}


def note_event(text: str) -> None:
    if currently_in_test_context():
        event(text)


class Agreement:
    """Drives a simulated session and checks the agreement of the two machines at every moment it applies."""

    def __init__(self, lb: SimulatedSession) -> None:
        self.lb = lb
        self.sent: list[str] = []
        lb.on_send = self.on_send

    def on_send(self, lb: SimulatedSession, send: SendGoal) -> None:
        self.sent.append(send.goal_uuid)
        if lb.quiescent:  # (a) the server in the state the client modelled accepts the goal
            decision = machine.accept(lb.server, send.goal, lb.config)
            assert isinstance(decision, outs.Accepted), (send, decision, lb.format_timeline())
            note_event("a: a sendable goal met a quiescent server")

    def check_view(self) -> None:
        lb = self.lb
        if not lb.statuses_in_flight:  # (b) every status delivered: the views agree
            expected = {view(lb.server)}
            server = lb.server
            if lb.config.compatibility is Compatibility.RMF_ROS2 and server.phase is DynamicState.WAITING:
                expected.add((DynamicState.RUNNING, server.seq, server.last_id))  # R17.4: the wire's view
            assert view(lb.client) in expected, lb.format_timeline()

    def command(self, outputs: tuple[client.ClientOutput, ...], quiet: bool, server: machine.State) -> None:
        config = self.lb.config
        for output in outputs:
            if not isinstance(output, Refused) or not quiet or server.shutdown or output.goal is None:
                continue
            reason = output.rejection.reason
            if reason is RejectReason.STALE_ID and config.id_policy is IdPolicy.ADAPTER:
                continue  # the server numbers children itself: no id rule to break
            if reason is RejectReason.CANCEL_IDLE and config.compatibility is Compatibility.RMF_ROS2:
                continue  # rmf_ros2 accepts an idle CANCEL and aborts it when it starts
            compat = config.compatibility is Compatibility.RMF_ROS2
            stale = self.lb.client.phase is DynamicState.RUNNING and server.phase is DynamicState.WAITING
            if reason is RejectReason.BUSY and stale and compat:
                continue  # R17.4: rmf_ros2's last status after a child's end says RUNNING
            # (c) a local refusal at a quiescent moment is the server's refusal, for the same reason
            decision = machine.accept(server, output.goal, config)
            assert isinstance(decision, outs.Rejected), (output, decision)
            assert decision.reason is reason, (output, decision)
            note_event(f"c: refused {reason.value}")

    def run(self, until: int | None = None) -> None:
        lb = self.lb
        while True:
            pending = lb.pending()
            if not pending or (until is not None and pending[0][0] > until):
                break
            lb.step()
            self.check_view()
        lb.run(until)

    def act(self, action: tuple[Any, ...]) -> None:
        lb = self.lb
        kind = action[0]
        quiet, server = lb.quiescent, lb.server
        if kind == "next":
            _, category, description, period, timeout = action
            self.command(
                lb.request_next(category, description, stubborn_period=period, timeout=timeout), quiet, server
            )
        elif kind == "next_plain":
            self.command(lb.request_next("go_to_place", '"pantry"'), quiet, server)
        elif kind == "cancel":
            self.command(lb.request_cancel(), quiet, server)
        elif kind == "finish":
            self.command(lb.request_finish(), quiet, server)
        elif kind == "begin":
            lb.begin('{"category": "patrol"}', event_id=action[1])
        elif kind in ("task_cancel", "task_kill", "interrupt", "resume"):
            getattr(lb, kind)()
        elif kind == "foreign_next":
            last = lb.server.last_id
            goal = Goal(
                dynamic_event_seq=lb.server.seq,
                event_type=EventType.NEXT,
                category="perform_action",
                description="{}",
                id=min(last + 1, U64),
            )
            lb.send_foreign(goal)
        elif kind == "foreign_cancel":
            lb.send_foreign(
                Goal(dynamic_event_seq=lb.server.seq, event_type=EventType.CANCEL, id=lb.server.current_id)
            )
        elif kind == "settle":  # deliver everything scheduled: the session becomes quiescent
            self.run()
            return
        else:
            self.run(lb.now + action[1])
            return
        self.check_view()


@given(
    first=BEGIN,
    actions=st.lists(ACTIONS, min_size=4, max_size=30),
    scripts=st.lists(SCRIPTS, max_size=4),
    options=OPTIONS,
    config=st.sampled_from(sorted(CONFIGS)),
    initial_seq=st.sampled_from((0, U32 - 1, U32)),
    seed=st.integers(0, 2**32 - 1),
)
def test_client_and_server_agree(
    first: tuple[Any, ...],
    actions: list[tuple[Any, ...]],
    scripts: list[ChildScript],
    options: Options,
    config: str,
    initial_seq: int,
    seed: int,
) -> None:
    server = attrs.evolve(machine.State.new("tinyRobot", "tinyRobot1"), seq=initial_seq)
    lb = SimulatedSession(
        ClientState.new(PREFIX, categories=CATEGORIES),
        server,
        CONFIGS[config],
        adapter=Adapter(scripts=tuple(scripts)),
        options=options,
        seed=seed,
    )
    agreement = Agreement(lb)
    agreement.check_view()
    for action in [first, *actions]:
        agreement.act(action)
    # wind down: release an interruption, let everything settle, then shut down and settle again
    if lb.server.interrupted:
        lb.resume()
    agreement.run()
    lb.shutdown()
    agreement.run()
    # (d) every goal the client sent has exactly one outcome, and the client holds no open goal
    answered = [outcome.goal_uuid for outcome in lb.outcomes]
    assert sorted(answered) == sorted(agreement.sent)
    assert lb.client.goals == ()
    assert lb.quiescent and view(lb.client) == view(lb.server)
    for outcome in lb.outcomes:
        note_event(f"outcome {outcome.kind.value}")


def test_agreement_example_with_a_race_and_a_timeout() -> None:
    lb = SimulatedSession(
        ClientState.new(PREFIX, categories=CATEGORIES),
        machine.State.new("f", "r"),
        CONFIG,
        adapter=Adapter(scripts=(ChildScript(finish_after=None),)),
        options=Options(delay=(D_MS, 5 * D_MS), start_delay=(0, 20 * D_MS), reorder=True),
        seed=11,
    )
    agreement = Agreement(lb)
    for action in [
        ("begin", 5),
        ("wait", SECOND),
        ("next", "go_to_place", '"a"', 0.0, 1),  # a 1 s timeout
        ("foreign_next",),
        ("wait", 3 * SECOND),
        ("next_plain",),
        ("wait", 3 * SECOND),
        ("finish",),
        ("wait", SECOND),
    ]:
        agreement.act(action)
    assert sorted(outcome.goal_uuid for outcome in lb.outcomes) == sorted(agreement.sent)
    assert all(isinstance(outcome, Outcome) for outcome in lb.outcomes)
