"""The help, the docs and the program agree: docs/cli.md's reference is the parser's, every
`pymunk-bot COMMAND --option` the docs show exists, and defaults the help states are true."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from pymunk_bot.cli import build_parser, main
from pymunk_bot.cli.reference import BEGIN, CLI_DOC, END, render, subcommands

REPO = Path(__file__).resolve().parents[2]
DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
COMMANDS = subcommands(build_parser())


def test_the_cli_reference_is_the_parsers():
    text = CLI_DOC.read_text(encoding="utf-8")
    documented = text[text.index(BEGIN):text.index(END) + len(END)]
    assert documented == render(), \
        "docs/cli.md is stale: run `python -m pymunk_bot.cli.reference --write`"


def code_of(path: Path) -> list[str]:
    """The code a page shows: its fenced blocks' lines and its inline `spans`."""
    text = path.read_text(encoding="utf-8")
    blocks = re.findall(r"```[^\n]*\n(.*?)```", text, flags=re.S)
    lines = [line for block in blocks for line in block.replace("\\\n", " ").splitlines()]
    prose = re.sub(r"```[^\n]*\n.*?```", "", text, flags=re.S)
    return lines + re.findall(r"`([^`\n]+)`", prose)


def documented_commands() -> list[tuple[str, str, str]]:
    """(page, command, code) for every `pymunk-bot COMMAND ...` in the docs."""
    found = []
    for page in DOCS:
        for code in code_of(page):
            for match in re.finditer(r"pymunk-bot ([a-z][a-z-]*)((?:(?!pymunk-bot ).)*)", code):
                found.append((page.name, match.group(1), match.group(2)))
    return found


def test_the_docs_show_commands():
    commands = {command for _, command, _ in documented_commands()}
    assert set(COMMANDS) <= commands | {"list"}, set(COMMANDS) - commands


@pytest.mark.parametrize("page, command, code", documented_commands())
def test_every_documented_command_and_option_exists(page, command, code):
    assert command in COMMANDS, f"{page}: `pymunk-bot {command}` is not a command"
    options = {o for a in COMMANDS[command]._actions for o in a.option_strings}
    for option in re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", code):
        assert option in options, f"{page}: `pymunk-bot {command}` has no {option}"


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_command_has_help(command, capsys):
    with pytest.raises(SystemExit) as exit_:
        main([command, "--help"])
    assert exit_.value.code == 0 and f"pymunk-bot {command}" in capsys.readouterr().out


def test_the_top_level_help_names_every_command(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    assert all(name in out for name in COMMANDS)
    assert "the parser" not in out  # the package docstring is not the program's description


def test_the_video_defaults_the_help_states_are_the_recorders():
    from pymunk_bot.viewer.recorder import DEFAULT_FPS

    fps = next(a for a in COMMANDS["run"]._actions if "--fps" in a.option_strings)
    for suffix, rate in DEFAULT_FPS.items():
        assert f"{rate:g} for {suffix}" in fps.help


def test_sweep_defaults_to_local_processes():
    backend = next(a for a in COMMANDS["sweep"]._actions if "--backend" in a.option_strings)
    assert backend.default == "process" and "(default: process)" in backend.help


def test_the_reference_writes_percent_signs_as_the_help_prints_them():
    """argparse %-formats an argument's help ('%%' prints '%') but not a description."""
    import argparse

    parser = argparse.ArgumentParser(prog="pymunk-bot")
    demo = parser.add_subparsers().add_parser("demo", help="a demo",
                                              description="the mean and 95 % interval")
    demo.add_argument("--level", type=int, default=95,
                      help="confidence in %% (default %(default)s, type %(type)s)")
    text = render(parser)
    assert "confidence in % (default 95, type int)" in text
    assert "the mean and 95 % interval" in text and "%%" not in text


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_no_argparse_escape_shows_in_help_or_docs(command, capsys):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    assert "%%" not in capsys.readouterr().out
    assert "%%" not in CLI_DOC.read_text(encoding="utf-8")


def test_no_doc_or_source_cites_a_path_of_the_authors_machine():
    """A reader has the repository, not the machine it was written on: every path a doc or a
    module cites must be one they can open."""
    files = [*DOCS, *(REPO / "docs").glob("*.py"), *(REPO / "pymunk_bot").rglob("*.py"),
             *(REPO / "examples").rglob("*.py")]
    cited = [f"{path.relative_to(REPO)}: {match.group(0)}" for path in files
             for match in re.finditer(r"(?<![\w.])/(?:work|home|Users)/[\w./-]+",
                                      path.read_text(encoding="utf-8"))]
    assert not cited, cited
