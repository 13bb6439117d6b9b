"""The client's watch on the server processes its goals went to (R21.4), without ROS."""

from __future__ import annotations

import pytest

from dynevent.client.restart import ASK_AGAIN_PERIOD, RestartWatch

OLD, NEW = frozenset({b"old"}), frozenset({b"old", b"new"})


@pytest.mark.spec("R21.4")
def test_goals_sent_before_a_new_server_process_are_asked_for_again_until_answered() -> None:
    watch = RestartWatch()
    assert watch.looking
    watch.sending(OLD)
    assert not watch.looking  # known: the binding does not ask the graph again for the next goal
    watch.sending(None)
    assert watch.servers == OLD
    assert watch.seen(OLD, {"a", "b"}, now=5.0) == []  # the same process: nothing lost
    assert watch.wait(5.0) is None
    assert watch.seen(NEW, {"a", "b"}, now=6.0) == ["a", "b"]  # a new process: both may be lost
    watch.asked(6.0)
    assert watch.wait(6.25) == pytest.approx(ASK_AGAIN_PERIOD - 0.25)
    assert watch.seen(NEW, {"a", "b"}, now=6.5) == []  # not due yet
    watch.answered("a")
    assert watch.seen(NEW, {"a", "b"}, now=7.0) == ["b"]  # due again, the answered one left out
    assert watch.seen(NEW, {"c"}, now=9.0) == []  # b ended some other way; c was sent after NEW came
    assert watch.wait(9.0) is None


@pytest.mark.spec("R21.4")
def test_with_no_goal_open_the_next_send_looks_at_the_processes_again() -> None:
    watch = RestartWatch()
    watch.sending(OLD)
    watch.idle()
    assert watch.looking
    watch.sending(NEW)  # the process the next goal goes to, whatever came between
    assert watch.seen(NEW, {"x"}, now=0.0) == []  # no new process since that goal was sent
