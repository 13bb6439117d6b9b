"""``dynevent demo``: a session a new user can read, in 100 columns, and as a sequence diagram."""

from __future__ import annotations

import re

import pytest

from dynevent.tools import demo

SEEDS = range(8)


@pytest.mark.parametrize("seed", SEEDS)
def test_the_timeline_fits_100_columns_without_trailing_space(seed: int) -> None:
    lines = demo.run_demo(seed).splitlines()
    assert max(len(line) for line in lines) <= demo.WIDTH
    assert not [line for line in lines if line != line.rstrip()]


def test_the_notation_is_explained_before_it_is_used() -> None:
    text = demo.run_demo(0)
    legend, timeline = text.split("-- 1.", 1)
    for used, explained in (
        ("0123..0000", "first and last four hex digits"),
        ("at L1 (4, 2)", "map L1, x = 4 m, y = 2 m"),
        ("stubborn", "stubborn period"),
        ("C->S", "C->S"),
        ("=>", "=>"),
    ):
        assert used in timeline and explained in legend, used
    assert "outcome completed (completed)" not in text  # said once


def test_the_closing_summary_counts_what_the_timeline_shows() -> None:
    tagged = demo.session_events(0)
    text = "\n".join(demo.summary(tagged))
    sent = sum(1 for _, event in tagged if event.direction == "client" and event.decision.startswith("send "))
    assert f"the client sent {sent} goals (3 of them raw" in text
    assert "rejected 2 (cancel_id_mismatch, inactive)" in text
    assert "refused 1 itself (inactive)" in text
    assert "1 accepted goal(s) beaten at start by a rival" in text
    assert "0.5 s clamped to 2 s" in text
    outcomes = [event.record["kind"] for _, event in tagged if event.kind == "outcome"]
    assert (
        f"{outcomes.count('completed')} completed" in text
        and f"{outcomes.count('canceled')} canceled" in text
    )
    assert demo.run_demo(0).rstrip().endswith(text.splitlines()[-1])


_MERMAID_LINE = re.compile(
    r"    (?:participant [CSA] as [\w ()]+"
    r"|Note over (?:C,A|C|S): [^;#\n]+"
    r"|(?:C->>S|S-->>C|S--xC|A->>S|S->>A): [^;#\n]+)"
)


@pytest.mark.parametrize("seed", SEEDS)
def test_the_sequence_diagram_is_mermaid_of_the_same_session(seed: int) -> None:
    lines = demo.mermaid(seed).splitlines()
    assert lines[0] == "sequenceDiagram"
    bad = [line for line in lines[1:] if not _MERMAID_LINE.fullmatch(line)]
    assert not bad
    tagged = demo.session_events(seed)
    goals = sum(1 for _, event in tagged if event.direction == "client->server")
    assert sum(1 for line in lines if line.startswith("    C->>S: ")) == goals
    assert sum(1 for line in lines if line.startswith("    Note over C,A: ")) == len(demo.STEPS)
    assert "S--xC: rejected: cancel_id_mismatch" in "\n".join(lines)
    assert "Note over S: aborted: race condition" in "\n".join(lines)


def test_the_docs_show_the_demos_diagram() -> None:
    from pathlib import Path

    page = (Path(__file__).resolve().parents[3] / "docs" / "demo.md").read_text(encoding="utf-8")
    assert "```mermaid\n" + demo.mermaid(0) + "```" in page, "regenerate with: dynevent demo --mermaid"
