"""A release says what it is: the version the package reports has its dated section in CHANGELOG.md
(Keep a Changelog), below an ``[Unreleased]`` section for what comes after it."""

from __future__ import annotations

import re
from pathlib import Path

import dynevent

CHANGELOG = Path(__file__).resolve().parents[2] / "CHANGELOG.md"


def test_the_version_has_its_dated_section_below_unreleased() -> None:
    text = CHANGELOG.read_text(encoding="utf-8")
    headings = re.findall(r"^## \[([^\]]+)\](?: - (\d{4}-\d{2}-\d{2}))?$", text, flags=re.MULTILINE)
    assert headings[0] == ("Unreleased", ""), headings[:2]
    released = dict(headings[1:])
    version = dynevent.__version__
    if ".dev" in version:  # between releases: the section comes with the release
        return
    assert released.get(version), f"CHANGELOG.md has no dated section for {version}: {headings[:3]}"
