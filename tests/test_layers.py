"""The package's shape: every module in a layer, no import cycles (grimp: imports inside
functions and for annotations counted), a top level a newcomer can read, and the bench's
section names, which the command line lists without importing the benchmarks."""
from __future__ import annotations

import tomllib
from pathlib import Path

import grimp

import pymunk_bot

from bench import SECTIONS
from pymunk_bot.cli.bench import SECTION_NAMES

def _cycles(graph: grimp.ImportGraph) -> list[set[str]]:
    """The strongly connected components of more than one module (Tarjan, iteratively)."""
    edges = {m: sorted(graph.find_modules_directly_imported_by(m)) for m in graph.modules}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []
    for root in sorted(edges):
        if root in index:
            continue
        work = [(root, 0)]
        while work:
            node, i = work.pop()
            if i == 0:
                index[node] = low[node] = len(index)
                stack.append(node)
                on_stack.add(node)
            targets = edges.get(node, [])
            if i < len(targets):
                work.append((node, i + 1))
                nxt = targets[i]
                if nxt not in index:
                    work.append((nxt, 0))
                elif nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
                continue
            if low[node] == index[node]:
                component = set()
                while True:
                    top = stack.pop()
                    on_stack.discard(top)
                    component.add(top)
                    if top == node:
                        break
                if len(component) > 1:
                    found.append(component)
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
    return found


def test_no_import_cycle_anywhere():
    # Imports inside functions count (grimp sees them), and so do ``if TYPE_CHECKING:`` ones.
    graph = grimp.build_graph("pymunk_bot", exclude_type_checking_imports=False)
    cycles = [sorted(m.removeprefix("pymunk_bot.") for m in c) for c in _cycles(graph)]
    assert cycles == []


def test_the_bench_names_its_sections_in_the_order_they_run():
    assert tuple(SECTIONS) == SECTION_NAMES


PACKAGE = Path(pymunk_bot.__file__).parent
PACKAGE_FILES = {"__init__.py", "py.typed"}  # what every typed package has


def _contracts() -> list[dict]:
    pyproject = tomllib.loads((PACKAGE.parent / "pyproject.toml").read_text())
    return pyproject["tool"]["importlinter"]["contracts"]


def _top_level() -> set[str]:
    """The package's top-level entries: its modules and subpackages, by import name."""
    return {p.stem for p in PACKAGE.iterdir()
            if p.name not in PACKAGE_FILES and p.name != "__pycache__"
            and (p.suffix == ".py" or (p / "__init__.py").is_file())}


def test_every_module_is_in_a_layer():
    layers = next(c for c in _contracts() if c.get("id") == "layers")
    named = {name.strip() for layer in layers["layers"] for name in layer.split(":")}
    assert _top_level() - named == set(), "add the new module to a layer in pyproject.toml"
    assert named - _top_level() == set()


def test_the_layers_debt_only_shrinks():
    # Imports that still run up the layers are listed in the contract; fix them, add none.
    layers = next(c for c in _contracts() if c.get("id") == "layers")
    assert len(layers["ignore_imports"]) <= 9


def test_the_top_level_is_a_short_list_of_concepts():
    entries = _top_level() | {p.name for p in PACKAGE.iterdir() if p.name in PACKAGE_FILES}
    assert len(entries) <= 24, sorted(entries)


def test_objects_read_no_private_state_of_others():
    # `other._name` (not self's or cls's): an owner gives a public method instead. What is
    # left reads argparse's internals (it has no public accessor for subcommands and help
    # expansion) and a pydantic private attribute of the same model class.
    import re

    reach = re.compile(r"\b([A-Za-z_][A-Za-z0-9_]*)(?:\[[^]]*\])?\.(_[a-z][A-Za-z0-9_]*)\b")
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for number, line in enumerate(path.read_text().splitlines(), 1):
            for owner, name in reach.findall(line):
                if owner not in ("self", "cls", "super") and not owner.startswith("_"):
                    found.append(f"{path.relative_to(PACKAGE)}:{number}: {owner}.{name}")
    assert len(found) <= 5, "\n".join(found)
