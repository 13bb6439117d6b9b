"""Every Python example in the documentation pages runs, and prints what its comments say."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"
PAGES = ["testing-your-implementation.md"]
EXAMPLES = [
    (page, index, block)
    for page in PAGES
    for index, block in enumerate(
        re.findall(r"```python\n(.*?)```", (DOCS / page).read_text(encoding="utf-8"), re.S)
    )
]


@pytest.mark.parametrize(("page", "index", "block"), EXAMPLES, ids=[f"{p}#{i + 1}" for p, i, _ in EXAMPLES])
def test_documentation_example_runs(
    page: str, index: int, block: str, capsys: pytest.CaptureFixture[str]
) -> None:
    exec(compile(block, f"docs/{page} example {index + 1}", "exec"), {"__name__": f"docs_example_{index}"})
    out = capsys.readouterr().out
    for expected in re.findall(r"print\(.*?\)\s*# (.+)", block):
        assert expected in out
