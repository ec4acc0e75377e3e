"""Every command of the README's "Command line" section runs (issue 12, item 10).

The commands are read from README.md itself, so the test follows the README. Each runs in a fresh, empty
folder (so output folders such as ``renders`` do not exist beforehand), with ``weather.epw`` copied from
tests/data (a two-day EPW). Commands with image-size options run with the sizes below appended (argparse
keeps the last value), which changes only the pixel count (or the Monte Carlo sample count), not the command:
the README gives the run time of the full size. Commands that need the Bruneton tables at their default size
(built once per session into the test cache, about a minute) are marked slow.
"""

from __future__ import annotations

import re
import shlex
import shutil
from pathlib import Path

import pytest

from skyscatter.cli import main

ROOT = Path(__file__).resolve().parents[1]
SMALL = {"demo": ["--width", "32", "--height", "18"], "sky": ["--width", "64"], "reference": ["--samples", "16"],
         "view": ["--check", "--port", "0"]}  # view: serve, fetch everything over HTTP and exit (no browser)


def readme_commands() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("### Command line", 1)[1]
    block = re.search(r"```sh\n(.*?)```", section, re.S).group(1)
    commands = []
    for line in block.splitlines():
        line = line.split("#", 1)[0].strip()
        if line.startswith("skyscatter "):
            commands.append(line)
    return commands


def _needs_tables(args: list[str]) -> bool:
    return args[0] in ("precompute", "export-luts", "view") or "bruneton" in args


@pytest.mark.parametrize(
    "command",
    [pytest.param(c, marks=pytest.mark.slow) if _needs_tables(shlex.split(c)[1:]) else c for c in readme_commands()],
)
def test_readme_command_runs(command, tmp_path, monkeypatch, capsys):
    args = shlex.split(command)[1:]
    if args[0] == "COMMAND":
        args[0] = "sky"
    shutil.copy(ROOT / "tests" / "data" / "weather.epw", tmp_path / "weather.epw")
    monkeypatch.chdir(tmp_path)
    code = main(args + SMALL.get(args[0], []))
    out, err = capsys.readouterr()
    assert code == 0, f"{command}: {err}"
    if "--help" not in args:
        assert out.strip()  # every command reports what it did


def test_readme_lists_the_commands():
    commands = readme_commands()
    assert len(commands) >= 10
    assert any(c.startswith("skyscatter skymatrix weather.epw") for c in commands)
