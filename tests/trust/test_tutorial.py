"""docs/tutorial.md is true: its files are written, its commands run in an empty folder with the
exit status it states, the output it shows is printed, and its Python runs."""
from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import pytest

from pymunk_bot.cli import main

TUTORIAL = Path(__file__).resolve().parents[2] / "docs" / "tutorial.md"


def blocks() -> list[tuple[str, str]]:
    """(language, text) of every fenced block, in order."""
    return re.findall(r"```(\w*)[^\n]*\n(.*?)```", TUTORIAL.read_text(encoding="utf-8"), re.S)


def test_the_tutorial_shows_files_commands_outputs_and_python():
    kinds = [kind for kind, _ in blocks()]
    assert {"yaml", "bash", "text", "python"} <= set(kinds)


def test_every_step_of_the_tutorial_works(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")  # no window: `run` goes headless
    output = ""
    ran = 0
    for kind, text in blocks():
        if kind == "yaml":
            name = re.match(r"# file: (\S+)\n", text)
            assert name, f"a YAML block of the tutorial names no file: {text[:40]!r}"
            (tmp_path / name.group(1)).write_text(text, encoding="utf-8")
        elif kind == "bash":
            for line in filter(None, map(str.strip, text.splitlines())):
                expected = re.search(r"#\s*exit (\d+)", line)
                words = shlex.split(line, comments=True)
                assert words[0] == "pymunk-bot", f"not a pymunk-bot command: {line}"
                status = main(words[1:])
                output = "".join(capsys.readouterr())
                assert status == (int(expected.group(1)) if expected else 0), (line, output)
                ran += 1
        elif kind == "text":  # the last command's output, except what measures the machine
            for line in text.splitlines():
                if line.strip() and "real time" not in line:
                    assert line in output.splitlines(), f"not printed: {line!r}\n{output}"
        elif kind == "python":
            exec(compile(text, str(TUTORIAL), "exec"), {"__name__": "tutorial"})
    assert ran >= 8
    assert (tmp_path / "first.png").stat().st_size > 10_000
    assert (tmp_path / "first.gif").stat().st_size > 10_000
    assert (tmp_path / "sweep.csv").read_text().count("\n") == 7  # header + 6 runs
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["passed"] and result["robots"]["r1"]["goal_reached"]
