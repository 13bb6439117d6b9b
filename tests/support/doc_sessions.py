"""Console sessions in the documentation: ```` ```console ```` blocks of ``$ command`` lines, each
followed by what it prints (tests/project/test_docs_examples.py runs them)."""

from __future__ import annotations

import re

CONSOLE = re.compile(r"```console\n(.*?)```", re.DOTALL)


def sessions(text: str) -> list[list[tuple[str, str]]]:
    """Each console block of ``text`` as its ``(command, expected output)`` pairs."""
    blocks = []
    for body in CONSOLE.findall(text):
        pairs: list[tuple[str, str]] = []
        for line in body.splitlines(keepends=True):
            if line.startswith("$ "):
                pairs.append((line[2:].rstrip("\n"), ""))
            else:
                command, output = pairs[-1]
                pairs[-1] = (command, output + line)
        blocks.append(pairs)
    return blocks
