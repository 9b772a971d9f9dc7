"""Optional features live in extras: importing one that is missing is one line naming the
install command, never a traceback."""
from __future__ import annotations

import importlib
from typing import Any

from pymunk_bot.config.errors import ScenarioError


def require(module: str, option: str, extra: str) -> Any:
    """Import ``module`` for ``option``, or raise a ScenarioError naming the install command
    of the extra that brings it (``pip install 'pymunk-bot[EXTRA]'``)."""
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise ScenarioError(option, "", f"needs the optional package '{exc.name or module}' "
                                        f"(install it with: pip install 'pymunk-bot[{extra}]')"
                            ) from None
