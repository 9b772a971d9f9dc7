"""The package's shape: import cycles (grimp, imports inside functions counted) and the bench's
section names, which the command line lists without importing the benchmarks."""
from __future__ import annotations

import grimp

from pymunk_bot.benchmarks import SECTIONS
from pymunk_bot.benchmarks.names import SECTION_NAMES

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
    # Imports inside functions count (grimp sees them); only ``if TYPE_CHECKING:`` ones do not.
    graph = grimp.build_graph("pymunk_bot", exclude_type_checking_imports=True)
    cycles = [sorted(m.removeprefix("pymunk_bot.") for m in c) for c in _cycles(graph)]
    assert cycles == []


def test_the_bench_names_its_sections_in_the_order_they_run():
    assert tuple(SECTIONS) == SECTION_NAMES
