"""Named extension points (drives, obstacle kinds, sensors, controllers, localizers).

Each entry is a factory plus the pydantic model of its YAML section; the scenario schema is
assembled from the registries (see ``config.schema``), so a plugin's keys are validated, and
its errors reported, like the built-ins'. Registries refuse duplicates and list valid names.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any, Callable, Generic, TypeVar

T = TypeVar("T")


@dataclass(frozen=True)
class Entry(Generic[T]):
    """One registered name: its factory and the config model of its section (None: no keys)."""

    name: str
    factory: T
    config: Any = None


class Registry(Generic[T]):
    """name -> (factory, config model); lookups of unknown names list the valid ones."""

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._items: dict[str, Entry[T]] = {}
        self.version = 0  # bumped on every change, so assembled schemas know when to rebuild

    def register(self, name: str, config: Any = None) -> Callable[[T], T]:
        """Decorator: ``@registry.register("name", ConfigModel)`` on a factory (usually a class)."""
        def decorate(item: T) -> T:
            self.add(name, item, config)
            return item
        return decorate

    def add(self, name: str, factory: T, config: Any = None) -> None:
        """Register ``factory`` (or a ``"module:attr"`` string) and its config model as
        ``name``; ValueError if the name is taken."""
        if name in self._items:
            raise ValueError(f"{self.kind} '{name}' is already registered")
        self._items[name] = Entry(name, factory, config)
        self.version += 1

    def remove(self, name: str) -> None:
        """Forget a name (tests that register temporary plugins clean up with this)."""
        self._items.pop(name, None)
        self.version += 1

    def entry(self, name: str) -> Entry[T]:
        """The entry registered as ``name``; KeyError listing the valid names if none is."""
        try:
            return self._items[name]
        except KeyError:
            valid = ", ".join(sorted(self._items))
            raise KeyError(f"unknown {self.kind} '{name}'; valid: {valid}") from None

    def get(self, name: str) -> T:
        """The factory registered as ``name`` (a ``"module:attr"`` string is imported now)."""
        entry = self.entry(name)
        if isinstance(entry.factory, str):
            module, _, attr = entry.factory.partition(":")
            factory = getattr(importlib.import_module(module), attr)
            entry = self._items[name] = Entry(name, factory, entry.config)
        return entry.factory

    def names(self) -> list[str]:
        """The registered names, sorted."""
        return sorted(self._items)

    def entries(self) -> list[Entry[T]]:
        """Every entry, in registration order (built-ins first)."""
        return list(self._items.values())

    def __contains__(self, name: object) -> bool:
        return name in self._items
