"""``dynevent diagram``: the server machine's phase diagram, drawn from
:data:`dynevent.server.machine.TRANSITIONS`.

docs/spec.md embeds the Mermaid form; the test suite checks it is up to date.
"""

from __future__ import annotations

import argparse

__all__ = ["FORMATS", "render", "run"]

#: The diagram formats :func:`render` can write.
FORMATS = ("mermaid", "dot")


def _label(input_kind: str, guard: str, rule: str) -> str:
    text = input_kind if not guard else f"{input_kind} [{guard}]"
    return f"{text} ({rule})"


def _mermaid() -> str:
    from dynevent.server.machine import (
        TRANSITIONS,  # here, not at import: the command line's help stays quick
    )

    lines = ["stateDiagram-v2", "    [*] --> INACTIVE"]
    for edge in TRANSITIONS:
        lines.append(
            f"    {edge.source.name} --> {edge.target.name}: {_label(edge.input, edge.guard, edge.rule)}"
        )
    return "\n".join(lines) + "\n"


def _dot() -> str:
    from dynevent.server.machine import TRANSITIONS

    lines = [
        "digraph dynamic_event {",
        "    rankdir=LR;",
        '    start [shape=point, label=""];',
        "    start -> INACTIVE;",
    ]
    for edge in TRANSITIONS:
        label = _label(edge.input, edge.guard, edge.rule).replace('"', '\\"')
        lines.append(f'    {edge.source.name} -> {edge.target.name} [label="{label}"];')
    lines.append("}")
    return "\n".join(lines) + "\n"


def render(fmt: str = "mermaid") -> str:
    """The diagram as text in ``fmt`` (``"mermaid"`` or ``"dot"``)."""
    if fmt == "mermaid":
        return _mermaid()
    if fmt == "dot":
        return _dot()
    raise ValueError(f"diagram format {fmt!r} is none of {', '.join(FORMATS)}")


def run(args: argparse.Namespace) -> int:
    """``dynevent diagram``: print the diagram in ``--format``; 0."""
    print(render(args.format), end="")
    return 0
