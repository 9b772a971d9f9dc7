"""A user's own localizer, imported from ``class_path: 'package.module:ClassName'``."""
from __future__ import annotations

from typing import Any

from pymunk_bot.controllers.python import import_module_attr
from pymunk_bot.localization.base import Localizer, LocalizerContext


def PythonLocalizer(config: Any, context: LocalizerContext) -> Localizer:
    """Build the user's :class:`Localizer` subclass named by ``config.class_path``, as
    ``Class(context, **params)`` (as a user's controller is built with its robot)."""
    cls = import_module_attr(config.class_path)
    if not (isinstance(cls, type) and issubclass(cls, Localizer)):
        raise ValueError(f"'{config.class_path}' is not a pymunk_bot.localization.Localizer subclass")
    if cls.update is Localizer.update:
        raise ValueError(f"'{config.class_path}' does not implement update(inputs)")
    try:
        return cls(context, **config.params)
    except TypeError as exc:
        raise ValueError(f"cannot build {config.class_path}(context, **params): {exc}") from None
