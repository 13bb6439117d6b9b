"""The field's descriptions through ``dynevent serve`` over DDS: what real clients send is served (R4.18).

A client that checks nothing locally sends the everyday ``go_to_place`` and
``perform_action`` descriptions of tests/descriptions to a ``serve`` process:
serve accepts exactly those the fleet adapter's schema accepts, runs each as
its description says, and refuses places off its map by name.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from ros_support import Child, Graph, child_env, finish, wait_for

from dynevent import client as cl
from dynevent.ros import DynamicEventClient
from support.field_cases import EVERYDAY_GO_TO_PLACE, EVERYDAY_PERFORM_ACTION

ROBOT = "fieldRobot"


def _serve(tmp_path: Path, **extra: Any) -> Child:
    config = tmp_path / "fleet.json"
    config.write_text(
        json.dumps(
            {
                "categories": {
                    "go_to_place": {"duration": 0.2, "report_every": 0.1},
                    "perform_action": {"duration": 0.2, "report_every": 0.1},
                    "sequence": {"report_every": 0.1},
                },
                **extra,
            }
        ),
        encoding="utf-8",
    )
    serve = Child(["-m", "dynevent", "serve", "--robot", ROBOT, "--rebegin", "0", "--config", str(config)])
    serve.wait_line("serving ")
    return serve


@pytest.fixture
def client(graph: Graph) -> Iterator[DynamicEventClient]:
    """A client that checks nothing locally: the server decides every description."""
    made: DynamicEventClient = graph.node(
        "field_client", lambda node: DynamicEventClient(node, "tinyRobot", ROBOT)
    )
    yield made


def _run(client: DynamicEventClient, category: str, description: Any) -> cl.Outcome:
    assert client.wait_for_status(20)
    outcome = client.next(category, json.dumps(description)).wait(20)
    assert isinstance(outcome, cl.Outcome), outcome
    if outcome.kind is not cl.OutcomeKind.REJECTED:  # the next goal's id follows this child's end
        wait_for(lambda: client.state.phase == 1 and client.state.current_id == outcome.id, "WAITING again")
    return outcome


@pytest.mark.spec("R4.18", "R4.10")
def test_serve_accepts_every_description_the_field_schema_accepts(tmp_path: Path, client: Any) -> None:
    serve = _serve(tmp_path)
    try:
        cases = [("go_to_place", *case) for case in EVERYDAY_GO_TO_PLACE]
        cases += [("perform_action", *case) for case in EVERYDAY_PERFORM_ACTION]
        for category, description, valid in cases:
            outcome = _run(client, category, description)
            expected = cl.OutcomeKind.COMPLETED if valid else cl.OutcomeKind.REJECTED
            assert outcome.kind is expected, (category, description, outcome, serve.output)
    finally:
        code = serve.stop()
    assert code == 0, serve.output


@pytest.mark.spec("R4.18")
def test_the_simulated_child_does_what_its_description_says(tmp_path: Path, client: Any) -> None:
    serve = _serve(tmp_path, places=["pantry", None, "lounge"], actions=["wave"])
    try:
        outcome = _run(client, "go_to_place", {"one_of": ["attic"]})
        assert outcome.kind is cl.OutcomeKind.REJECTED
        refusal = "refused: description_invalid: the description does not fit the 'go_to_place' category: "
        serve.wait_line(refusal + '/one_of/0: "attic" is not a waypoint', timeout=15)  # serve logs it later
        progress: list[cl.Progress] = []
        place = {"place": {"waypoint": 1, "orientation": 1.5}, "followed_by": ["lounge"]}
        run = client.next("go_to_place", json.dumps(place), on_progress=progress.append)
        assert run.wait(20).kind is cl.OutcomeKind.COMPLETED
        logs = [entry.text for update in progress for entry in update.logs]
        assert any(text.startswith("go_to_place #1 (facing 1.5 rad), then lounge: ") for text in logs), logs
        wait_for(lambda: client.state.phase == 1, "WAITING")
        progress.clear()
        action = {"category": "wave", "description": {}, "unix_millis_action_duration_estimate": 500}
        sequence = [
            {"category": "go_to_place", "description": "pantry"},
            {"category": "perform_action", "description": action},
        ]
        run = client.next("sequence", json.dumps(sequence), on_progress=progress.append)
        assert run.wait(20).kind is cl.OutcomeKind.COMPLETED
        logs = [entry.text for update in progress for entry in update.logs]
        assert "now activity 2 of 2: perform_action wave" in logs, logs
        assert any(text.startswith("activity 2 of 2: perform_action wave: 0 of 0.5 s") for text in logs), logs
    finally:
        code = serve.stop()
    assert code == 0, serve.output


@pytest.mark.spec("R4.18", "R20.1")
def test_send_sends_the_fields_descriptions_and_refuses_locally_what_the_server_would(tmp_path: Path) -> None:
    serve = _serve(tmp_path)
    try:
        for description in ("3", '{"waypoint": "A", "orientation": 1.57}', '{"one_of": [{"waypoint": 2}]}'):
            done = _send("--description", description)
            assert done.returncode == 0 and "outcome: completed" in done.stdout, done.stdout + done.stderr
        file = tmp_path / "action.json"
        file.write_text('{"category": "wave", "description": {"arm": "left"}}', encoding="utf-8")
        done = _send("--category", "perform_action", "--description", f"@{file}")
        assert done.returncode == 0 and "outcome: completed" in done.stdout, done.stdout + done.stderr
        refused = _send("--description", '{"one_of": ["A", 5.5]}')
        assert refused.returncode == 1
        assert "not sent: the robot would refuse it: description_invalid:" in refused.stdout
        assert "/one_of/1: 5.5 is not a place" in refused.stdout
        bad = _send("--description", "{nope")
        assert (
            bad.returncode == 2 and "--description: not JSON" in bad.stderr and "Traceback" not in bad.stderr
        )
    finally:
        code = serve.stop()
    assert code == 0, serve.output


def _send(*args: str) -> Any:
    import subprocess
    import sys

    process = subprocess.Popen(
        [sys.executable, "-m", "dynevent", "send", "--robot", ROBOT, "--timeout", "20", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=child_env(),
    )
    return finish(process, 40)
