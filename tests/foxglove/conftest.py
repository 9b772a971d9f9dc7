"""Foxglove tests need the optional packages of `pip install 'pymunk-bot[foxglove]'`."""
from __future__ import annotations

import pytest

pytest.importorskip("foxglove")
pytest.importorskip("mcap")
pytest.importorskip("mcap_protobuf")
