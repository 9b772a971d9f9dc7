"""The one error every view raises when it cannot show anything here."""
from __future__ import annotations


class ViewerUnavailable(RuntimeError):
    """The window cannot open here; ``str()`` says why in one line."""
