"""docs/testing.md's guide to a site across hosts runs as written and prints what it says."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
from sites import START

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.spec("R21.5")
def test_the_guide_to_a_site_across_hosts_runs_as_written(tmp_path: Path) -> None:
    text = (ROOT / "docs" / "testing.md").read_text(encoding="utf-8")
    section = text[text.index("## 6. Across hosts") :]
    (block,) = re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)
    block = block.replace('Path("/tmp/site")', f"Path({str(tmp_path / 'site')!r})")
    expected = re.findall(r"^print\(.*\)  # (.*)$", block, flags=re.MULTILINE)
    assert expected, "the guide prints nothing to check"
    done = subprocess.run(  # from the project's root, as the guide says
        [sys.executable, "-c", block],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=START * 4,
        check=False,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.splitlines() == expected, done.stdout + done.stderr
