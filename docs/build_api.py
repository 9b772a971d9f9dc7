"""Build the API reference (HTML) from the docstrings of pymunk-bot's public modules, with pdoc.

    python docs/build_api.py [--out docs/api]      # then open docs/api/index.html

Run by .ci/run: a docstring pdoc cannot render (an annotation that does not resolve, a name in
``__all__`` that does not exist) or a ``>>>`` example in a docstring that fails, fails the build,
one line per problem; ``--strict`` also fails on a public class or function with no docstring
(9 methods in the core today). The output is generated, not committed: it is about 4 MB of
HTML that any checkout rebuilds in 2 s (see .gitignore). Needs pdoc (the ``dev`` extra).
"""
from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from pathlib import Path

# The public API (/work/shared/CONTRACT.md and the docs' examples), in the order of the index.
PUBLIC_MODULES = [
    "pymunk_bot", "pymunk_bot.engine.simulation", "pymunk_bot.robots.robot", "pymunk_bot.engine.replicas",
    "pymunk_bot.robots.command", "pymunk_bot.config.errors", "pymunk_bot.config", "pymunk_bot.plugins",
    "pymunk_bot.config.registry", "pymunk_bot.controllers", "pymunk_bot.sensors",
    "pymunk_bot.localization", "pymunk_bot.envs", "pymunk_bot.outcomes.runlog", "pymunk_bot.sweep",
    "pymunk_bot.policy.io", "pymunk_bot.policy.files", "pymunk_bot.outcomes.navigation",
    "pymunk_bot.benchmark",
]
DEFAULT_OUT = Path(__file__).resolve().parent / "api"


def materialize_lazy_exports(module_names: list[str]) -> None:
    """Load the names packages export lazily (a module ``__getattr__``), so pdoc finds each
    name of ``__all__`` in the module's namespace as ``from package import name`` would."""
    for name in module_names:
        module = importlib.import_module(name)
        for export in getattr(module, "__all__", []):
            if export not in vars(module) and hasattr(module, export):  # pdoc reports the rest
                setattr(module, export, getattr(module, export))


def undocumented(module_names: list[str]) -> list[str]:
    """The public classes, functions and methods (of ``__all__`` where a module has one) that
    have no docstring of their own."""
    import pdoc.doc

    missing: list[str] = []

    def visit(members: list[pdoc.doc.Doc]) -> None:
        for member in members:
            if member.name.startswith("_") or not member.taken_from[0].startswith("pymunk_bot"):
                continue
            if isinstance(member, (pdoc.doc.Class, pdoc.doc.Function)) and not member.docstring:
                missing.append(member.fullname)
            if isinstance(member, pdoc.doc.Class):
                visit(member.own_members)

    for name in module_names:
        visit(pdoc.doc.Module(importlib.import_module(name)).own_members)
    return sorted(set(missing))


def failed_examples(module_names: list[str]) -> list[str]:
    """Run the ``>>>`` examples in the modules' docstrings; one line per failing module."""
    import doctest

    failures = []
    for name in module_names:
        result = doctest.testmod(importlib.import_module(name), report=True,
                                 optionflags=doctest.ELLIPSIS)
        if result.failed:
            failures.append(f"{name}: {result.failed} of {result.attempted} docstring "
                            "examples fail")
    return failures


def build(out: Path, module_names: list[str] = PUBLIC_MODULES) -> list[str]:
    """Write the reference under ``out``; return the problems found (empty when it is clean):
    pdoc's warnings and docstring examples that fail."""
    try:
        import pdoc
        import pdoc.render
    except ImportError:
        raise SystemExit("error: the API reference needs pdoc: pip install -e '.[dev]'") from None
    materialize_lazy_exports(module_names)
    pdoc.render.configure(docformat="markdown", footer_text="pymunk-bot",
                          search=True, show_source=False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pdoc.pdoc(*module_names, output_directory=out)
    # pdoc's own warnings, not the deprecations of libraries it imports
    problems = [str(w.message) for w in caught if "pdoc" in w.filename]
    return problems + failed_examples(module_names)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output folder")
    parser.add_argument("--strict", action="store_true",
                        help="also fail on a public class or function with no docstring")
    args = parser.parse_args(argv)
    problems = build(args.out)
    missing = [f"no docstring: {name}" for name in undocumented(PUBLIC_MODULES)]
    for problem in problems + (missing if args.strict else []):
        print(f"error: API reference: {problem}", file=sys.stderr)
    if not args.strict and missing:
        print(f"note: API reference: {len(missing)} public names have no docstring "
              f"(--strict lists them)", file=sys.stderr)
    failed = bool(problems or (args.strict and missing))
    if not failed:
        print(f"API reference written to {args.out / 'index.html'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
