"""Registers ``pymunk_bot/Navigation-v0`` with Gymnasium as Gymnasium is imported.

Gymnasium 1.0 removed the plugin system that loaded packages' ``gymnasium.envs`` entry points:
an id is known only once the module that registers it has run. ``pymunk_bot-gymnasium.pth``
(installed next to this module by a regular ``pip install``; see setup.py) imports this module
at interpreter start-up, so that ``gym.make("pymunk_bot/Navigation-v0")`` works in an
interpreter that never imported pymunk_bot. Start-up cost: this module (standard library only)
and one finder on ``sys.meta_path`` that answers only for ``gymnasium`` and leaves once
Gymnasium is imported. The registration names the env by strings, so pymunk_bot itself is
imported only when the env is made. It never raises: a start-up hook must not break Python.
"""
from __future__ import annotations

import importlib.util
import sys
from importlib.machinery import ModuleSpec
from types import ModuleType  # (no typing: every interpreter start pays for this module)

NAVIGATION_ID = "pymunk_bot/Navigation-v0"
NAVIGATION_SPEC: dict[str, object] = {
    "id": NAVIGATION_ID,
    "entry_point": "pymunk_bot.envs.navigation:NavigationEnv",
    "vector_entry_point": "pymunk_bot.envs.vector:NavigationVectorEnv",
    "disable_env_checker": False,
}


def register(gymnasium: ModuleType) -> None:
    """Register the pymunk_bot ids with this Gymnasium (idempotent)."""
    if NAVIGATION_ID not in gymnasium.registry:
        gymnasium.register(**NAVIGATION_SPEC)


class RegisterWhenImported:
    """A meta path finder that finds nothing itself: when ``gymnasium`` is looked for, it takes
    the spec the other finders give and registers the ids right after the package has run."""

    def find_spec(self, name: str, path: object = None, target: object = None
                  ) -> ModuleSpec | None:
        if name != "gymnasium":
            return None
        sys.meta_path.remove(self)  # from now on Gymnasium is found as usual
        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        run = spec.loader.exec_module  # this loader object serves this one import

        def exec_module(module: ModuleType) -> None:
            run(module)
            try:
                register(module)
            except Exception as exc:  # a Gymnasium that changed its API must still import
                print(f"pymunk_bot: could not register {NAVIGATION_ID} with Gymnasium "
                      f"({exc}); import pymunk_bot.envs to register it", file=sys.stderr)

        spec.loader.exec_module = exec_module  # type: ignore[method-assign]
        return spec


def install() -> None:
    """Register now if Gymnasium is already imported, else when it is."""
    try:
        if "gymnasium" in sys.modules:
            register(sys.modules["gymnasium"])
        elif not any(isinstance(f, RegisterWhenImported) for f in sys.meta_path):
            sys.meta_path.insert(0, RegisterWhenImported())
    except Exception:  # noqa: BLE001  never break interpreter start-up
        pass


install()
