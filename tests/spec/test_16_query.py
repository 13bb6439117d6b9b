"""§16. Description query: the tests of the rules of docs/spec.md §16.

The section's conformance vectors are src/dynevent/conformance/vectors/16-query.json.
"""

from __future__ import annotations

import pytest

from dynevent.server import outputs as outs
from dynevent.wire.messages import DescriptionResponse
from support.scenario import (
    DESC,
    Run,
    deferred,
    finished_goal,
    running,
    u,
    waiting,
)


def _described(running: bool = False, text: str = "", description: str = "", id: int = 0) -> tuple[object]:
    return (
        outs.DescriptionAnswer(
            response=DescriptionResponse(running=running, status=text, description=description, id=id)
        ),
    )


# --------------------------------------------------------------------------- R16.1


@pytest.mark.spec("R16.1")
def test_description_query_while_inactive() -> None:
    run = Run()
    assert run.query() == _described()
    run = waiting()
    run.submit(u(1), finished_goal(1))
    assert run.query() == _described()
    assert run.state == run.before
    run = running()
    run.shutdown()
    assert run.query() == _described()


# --------------------------------------------------------------------------- R16.2


@pytest.mark.spec("R16.2")
def test_description_query_while_waiting() -> None:
    run = waiting(event_id=40)
    assert run.query() == _described(True, "standby", DESC, 40)
    assert run.state == run.before


@pytest.mark.spec("R16.2")
def test_description_query_while_running() -> None:
    run = running(child_id=41, event_id=40)
    run.progress("delayed")
    assert run.query() == _described(True, "delayed", DESC, 41)
    run.task_cancel()
    assert run.query() == _described(True, "canceled", DESC, 41)


@pytest.mark.spec("R16.2", "R6.3")
def test_description_query_with_a_deferred_child() -> None:
    run = deferred(child_id=5)
    assert run.query() == _described(True, "queued", DESC, 5)
