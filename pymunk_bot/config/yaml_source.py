"""Reading YAML safely: bounded size, depth and alias expansion; the line of every key kept;
duplicate keys refused. Everything here runs before pydantic sees the data.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from pymunk_bot.config.errors import ScenarioError

MAX_FILE_BYTES = 1 << 20  # 1 MiB: a scenario is a page of text, not a data set
MAX_DEPTH = 32  # nesting of mappings and lists (a scenario needs about 6)
MAX_NODES = 200_000  # values after alias expansion ("billion laughs" stops here)


def read_text(path: Path, source: str) -> str:
    """The file's text, refusing what is not a regular file of at most MAX_FILE_BYTES.

    ``stat`` comes first so a named pipe or a device is never opened (opening a FIFO blocks);
    at most MAX_FILE_BYTES + 1 bytes are read, so a file that keeps growing cannot hang us.
    """
    try:
        info = path.stat()
    except FileNotFoundError:
        raise ScenarioError(source, "", "file not found") from None
    except OSError as exc:
        raise ScenarioError(source, "", f"cannot read: {exc.strerror or exc}") from None
    if stat.S_ISDIR(info.st_mode):
        raise ScenarioError(source, "", "is a directory, not a scenario file")
    if not stat.S_ISREG(info.st_mode):
        raise ScenarioError(source, "", "is not a regular file (a pipe or a device?)")
    if info.st_size > MAX_FILE_BYTES:
        raise ScenarioError(source, "", f"file too large: {info.st_size} bytes "
                                        f"(at most {MAX_FILE_BYTES} = 1 MiB)")
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as f:
            data = f.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise ScenarioError(source, "", f"cannot read: {exc.strerror or exc}") from None
    if len(data) > MAX_FILE_BYTES:
        raise ScenarioError(source, "", f"file too large (at most {MAX_FILE_BYTES} bytes = 1 MiB)")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ScenarioError(source, "", f"not UTF-8 text (byte {exc.start})") from None


# libyaml's parser when PyYAML has it: ten times faster on a 1 MiB file, same nodes and marks.
# The checker sees one class (a runtime choice between two cannot be a base class to it).
if TYPE_CHECKING:
    from yaml import SafeLoader as _SafeLoader
else:
    _SafeLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class _StrictLoader(_SafeLoader):
    """SafeLoader that refuses duplicate and non-scalar keys (PyYAML keeps the last duplicate and
    fails with a TypeError on a list key), and reports unreadable tagged scalars with their line."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: set[Any] = set()
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue  # `<<: *base` merges, as safe_load does; explicit keys override it
            if not isinstance(key_node, yaml.ScalarNode):
                raise yaml.constructor.ConstructorError(
                    None, None, "a key must be a plain word, not a list or mapping",
                    key_node.start_mark)
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key '{key}'", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)

    def construct_object(self, node: yaml.Node, deep: bool = False) -> Any:
        try:
            return super().construct_object(node, deep=deep)
        except (ValueError, TypeError, OverflowError) as exc:  # `!!float abc`, a 5000-digit int
            tag = node.tag.rsplit(":", 1)[-1]
            raise yaml.constructor.ConstructorError(
                None, None, f"cannot read {_short(node)} as {tag} ({type(exc).__name__})",
                node.start_mark) from None


def _short(node: yaml.Node) -> str:
    value = node.value if isinstance(node, yaml.ScalarNode) else node.id
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "...'"


def _check_depth(text: str) -> None:
    """Bound nesting before composing (PyYAML's composer recurses: 1000 levels overflow)."""
    depth = 0
    for event in yaml.parse(text, Loader=_StrictLoader):
        if isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            depth += 1
            if depth > MAX_DEPTH:
                raise yaml.constructor.ConstructorError(
                    None, None, f"nested too deeply (at most {MAX_DEPTH} levels)",
                    event.start_mark)
        elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
            depth -= 1


def _check_expansion(root: yaml.Node | None) -> None:
    """Bound the number of values after aliases expand; refuse recursive aliases.

    Each distinct node's expanded size is computed once (iteratively), so a 'billion laughs'
    document of a few lines is measured in microseconds and refused.
    """
    if root is None:
        return
    size: dict[int, int] = {}
    on_path: set[int] = set()
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, done = stack.pop()
        key = id(node)
        children = _children(node)
        if done:
            on_path.discard(key)
            total = 1 + sum(size[id(c)] for c in children)
            if total > MAX_NODES:
                raise yaml.constructor.ConstructorError(
                    None, None, f"too many values once aliases expand (more than {MAX_NODES})",
                    node.start_mark)
            size[key] = total
            continue
        if key in size:
            continue
        if key in on_path:
            raise yaml.constructor.ConstructorError(
                None, None, "an alias refers to a value that contains it", node.start_mark)
        on_path.add(key)
        stack.append((node, True))
        for child in children:
            if id(child) in on_path:
                raise yaml.constructor.ConstructorError(
                    None, None, "an alias refers to a value that contains it", child.start_mark)
            if id(child) not in size:
                stack.append((child, False))


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    return []


def parse_yaml(text: str, source: str) -> tuple[Any, yaml.Node | None]:
    """The document as Python data plus its node tree (for line numbers)."""
    if len(text) > MAX_FILE_BYTES:
        raise ScenarioError(source, "", f"document too large (at most {MAX_FILE_BYTES} characters)")
    try:
        _check_depth(text)
        node = yaml.compose(text, Loader=_StrictLoader)
        _check_expansion(node)
        loader = _StrictLoader(text)
        try:
            data = loader.get_single_data()
        finally:
            loader.dispose()
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        problem = exc.problem or exc.context or "invalid YAML"
        opened = exc.context_mark
        if "flow" in (exc.context or "") and opened is not None and line is not None \
                and opened.line + 1 < line:  # PyYAML notices an unclosed [ or { a line later
            what = (exc.context or "").removeprefix("while parsing ")
            problem = f"{what} is not closed ({problem} on line {line})"
            line = opened.line + 1
        if not isinstance(exc, yaml.constructor.ConstructorError):
            problem = f"YAML syntax error: {problem}"
        raise ScenarioError(source, "", problem, line) from None
    except yaml.YAMLError as exc:
        raise ScenarioError(source, "", f"YAML error: {exc}") from None
    except RecursionError:
        raise ScenarioError(source, "", f"nested too deeply (at most {MAX_DEPTH} levels)") from None
    return data, node


def line_of(node: yaml.Node | None, loc: tuple) -> int | None:
    """1-based line of the deepest node on the key path ``loc`` that exists."""
    line = node.start_mark.line + 1 if node is not None else None
    for part in loc:
        child = None
        if isinstance(node, yaml.MappingNode):
            for key_node, value_node in node.value:
                if key_node.value == part:
                    child, line = value_node, key_node.start_mark.line + 1
                    break
        elif isinstance(node, yaml.SequenceNode) and isinstance(part, int) and part < len(node.value):
            child = node.value[part]
            line = child.start_mark.line + 1
        if child is None:
            break
        node = child
    return line
