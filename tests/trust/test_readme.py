"""A newcomer's README: right after the two set-up commands it says what the project can do and
where each thing is explained; its Python runs from any folder; its sweep passes as shown."""
from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from pymunk_bot.cli import main

REPO = Path(__file__).resolve().parents[2]
README = (REPO / "README.md").read_text(encoding="utf-8")
FIRST_SCREEN = 60  # [lines] a terminal or a repository page shows before scrolling far


def blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", README, flags=re.S)


def command(prefix: str) -> str:
    """The README's `pymunk-bot ...` line that starts with ``prefix``, comment removed."""
    lines = [line for block in blocks("bash") for line in block.splitlines()]
    found = [line for line in lines if line.startswith(prefix)]
    assert len(found) == 1, f"the README shows {len(found)} `{prefix}` lines"
    return shlex.split(found[0], comments=True)


def test_the_first_screen_maps_every_capability_to_its_doc():
    head = "\n".join(README.splitlines()[:FIRST_SCREEN])
    setup = head.index("```bash")
    table = head[head.index("```", setup + 3) + 3:]
    assert re.search(r"^\| *you want to *\| *read *\|", table, flags=re.M | re.I), \
        "no capability -> doc table right after the set-up commands"
    linked = set(re.findall(r"\]\(([^)#]+)[^)]*\)", table))
    pages = {f"docs/{page.name}" for page in (REPO / "docs").glob("*.md")}
    assert pages <= linked, f"not in the first screen: {sorted(pages - linked)}"
    assert "examples/quickstart.ipynb" in linked and "docs/build_api.py" in linked


def test_every_link_of_the_readme_leads_to_a_file():
    for target in re.findall(r"\]\(([^)#]+)[^)]*\)", README):
        if "://" in target:
            continue
        assert (REPO / target).exists(), f"README links to {target}, which does not exist"


def test_the_docs_list_of_the_layout_names_every_page():
    layout = README[README.index("## Layout"):]
    docs_line = layout[layout.index("docs/  "):].split("\n\n")[0].split("```")[0]
    for page in (REPO / "docs").glob("*.md"):
        assert re.search(rf"\b{page.stem}\b", docs_line), f"{page.stem} not in {docs_line!r}"


def test_the_readmes_python_runs_outside_the_checkout(tmp_path, monkeypatch):
    (python,) = blocks("python")
    monkeypatch.chdir(tmp_path)  # no scenarios/ folder: only shipped names work here
    exec(compile(python, "README.md", "exec"), {"__name__": "readme"})


def test_the_readmes_sweep_passes_on_a_few_of_its_seeds(tmp_path, monkeypatch):
    """The README's sweep, on its first two seeds, serially (the whole of it: the slow test)."""
    words = command("pymunk-bot sweep ")
    seeds = words.index("--seeds") + 1
    words[seeds] = "0:2"
    monkeypatch.chdir(tmp_path)
    assert main([*words[1:], "--backend", "serial", "--no-progress"]) == 0


@pytest.mark.slow
def test_the_readmes_sweep_passes_as_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main([*command("pymunk-bot sweep ")[1:], "--workers", "2", "--no-progress"]) == 0


def test_the_readme_says_what_the_sweeps_exit_status_means():
    line = next(line for block in blocks("bash") for line in block.splitlines()
                if line.startswith("pymunk-bot sweep "))
    following = README[README.index(line):][:400].lower()
    assert "exit 1" in following and "exit 0" in following
