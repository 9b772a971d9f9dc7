"""Where a user's class named by ``class_path: 'package.module:ClassName'`` is found, and a check
of it that runs no user code: the module is found on disk and its source parsed.

The folders looked in: next to the scenario file, then the folders above it, then the current
folder, then ``sys.path``. Importing the class is the simulation's business
(``controllers/python.py``), not the configuration's.
"""
from __future__ import annotations

import ast
import importlib.machinery
import importlib.util
import os
import sys
from pathlib import Path


def search_dirs(base_dir: str | Path | None) -> list[Path]:
    """The scenario's folder and those above it, then the current folder."""
    dirs = []
    if base_dir is not None:
        base = Path(base_dir).resolve()
        dirs += [base, *base.parents]
    dirs.append(Path(os.getcwd()))
    return dirs


def module_home(module_name: str, base_dir: str | Path | None) -> Path | None:
    """The first search folder holding the module's top-level package (None: use sys.path)."""
    top = module_name.split(".")[0]
    if top in sys.modules or top == "pymunk_bot":
        return None
    for directory in search_dirs(base_dir):
        if importlib.machinery.PathFinder.find_spec(top, [str(directory)]) is not None:
            return directory
    return None


def check_class_path(class_path: str, base_dir: str | Path | None = None) -> None:
    """Find the module and check the class without running user code; ValueError if wrong.

    The module is found on disk and its source parsed (ours too: configuration imports no
    controller), which catches a missing module or class, or one with no ``compute`` of its own.
    """
    module_name, _, attr = class_path.partition(":")
    home = module_home(module_name, base_dir)
    for _ in range(MAX_REEXPORTS + 1):
        origin = _find_source(module_name, home)
        if origin is None:
            raise ValueError(f"cannot import module '{module_name}': not found next to the "
                             "scenario, in the folders above it, the current folder or sys.path")
        if origin.suffix != ".py" or "." in attr:
            return  # compiled or nested: checked when the simulation imports it
        try:
            tree = ast.parse(origin.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, SyntaxError, ValueError) as exc:
            raise ValueError(f"cannot read '{origin}': {type(exc).__name__}: {exc}") from None
        source = _reexported_from(tree, module_name, origin, attr)
        if source is None:
            _check_source(tree, module_name, attr, class_path)
            return
        module_name = source  # `from .base import Controller`: the class is defined there


MAX_REEXPORTS = 3  # `from .x import Name` links followed to the class's own module


def _reexported_from(tree: ast.Module, module_name: str, origin: Path, attr: str) -> str | None:
    """The module ``attr`` is imported from in this module's top level (None: not imported by
    a ``from ... import``, or not defined by one)."""
    package = module_name if origin.name == "__init__.py" else module_name.rpartition(".")[0]
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and any((a.asname or a.name) == attr and a.name == attr
                                                    for a in node.names):
            if node.level == 0:
                return node.module
            base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
            return f"{base}.{node.module}" if node.module else base
    return None


def _find_source(module_name: str, home: Path | None) -> Path | None:
    """The file of a (dotted) module, found without importing it; None if absent."""
    parts = module_name.split(".")
    if home is None:
        try:
            spec = importlib.util.find_spec(parts[0])
        except (ImportError, ValueError):
            return None
    else:
        spec = importlib.machinery.PathFinder.find_spec(parts[0], [str(home)])
    for part in parts[1:]:
        if spec is None or not spec.submodule_search_locations:
            return None
        spec = importlib.machinery.PathFinder.find_spec(part, list(spec.submodule_search_locations))
    if spec is None:
        return None
    return Path(spec.origin) if spec.origin else Path(os.devnull)


def _abstract(function: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    """A method whose body only raises NotImplementedError (after its docstring)."""
    body = [n for n in function.body
            if not (isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant))]
    return (len(body) == 1 and isinstance(body[0], ast.Raise) and body[0].exc is not None
            and "NotImplementedError" in ast.unparse(body[0].exc))


def _check_source(tree: ast.Module, module_name: str, attr: str, class_path: str) -> None:
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name == attr:
            own = {n.name for n in node.body if isinstance(n, (ast.FunctionDef,
                                                               ast.AsyncFunctionDef))
                   and not _abstract(n)}
            bases = {ast.unparse(b).rsplit(".", 1)[-1] for b in node.bases}
            if "compute" not in own and bases <= {"Controller", "object"}:
                raise ValueError(f"'{class_path}' has no compute(observation) method of its own")
            return
    bound = {t.id for n in tree.body if isinstance(n, (ast.Assign, ast.AnnAssign))
             for t in (n.targets if isinstance(n, ast.Assign) else [n.target])
             if isinstance(t, ast.Name)}
    bound |= {(a.asname or a.name).split(".")[0] for n in tree.body
              if isinstance(n, (ast.Import, ast.ImportFrom)) for a in n.names}
    if attr not in bound and not any(isinstance(n, (ast.If, ast.Try)) for n in tree.body):
        raise ValueError(f"module '{module_name}' has no attribute '{attr}'")
