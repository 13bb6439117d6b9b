"""Every Python example in README.md runs."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import dynevent

README = Path(__file__).resolve().parents[2] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.DOTALL)


def test_readme_has_examples() -> None:
    assert BLOCKS


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_example_runs(index: int, capsys: pytest.CaptureFixture[str]) -> None:
    exec(compile(BLOCKS[index], f"README.md example {index + 1}", "exec"), {})
    out = capsys.readouterr().out
    for expected in re.findall(r"print\(.*?\)\s*# (.+)", BLOCKS[index]):
        assert expected in out


ROOT = README.parent
LINK = re.compile(re.escape(dynevent.HOME) + r"/blob/main/([\w/-]+(?:\.[\w-]+)*)")


def test_readme_links_are_absolute_and_name_files_that_exist() -> None:
    """The package index shows README.md away from the repository: every link must be absolute."""
    text = README.read_text(encoding="utf-8")
    assert not re.findall(r"\]\((?!https?://)[^)]*\)", text), "a relative link"
    targets = LINK.findall(text)
    assert targets
    for target in targets:
        assert (ROOT / target).is_file(), target


def test_the_command_lines_links_and_the_package_urls_name_files_that_exist() -> None:
    from dynevent.tools import cli

    help_texts = "\n".join(
        cli_output(cli.main, [*command, "--help"]) for command in ([], ["check"], ["vectors"], ["diagram"])
    )
    pyproject = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    targets = LINK.findall(help_texts) + LINK.findall(pyproject)
    assert len(targets) >= 5
    for target in targets:
        assert (ROOT / target).is_file(), target
    assert f'Homepage = "{dynevent.HOME}"' in pyproject


def cli_output(main: object, argv: list[str]) -> str:
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):
        main(argv)  # type: ignore[operator]
    return out.getvalue()
