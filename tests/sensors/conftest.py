"""The exact-caster tests run on both tracers: compiled (numba) and numpy."""
from __future__ import annotations

import pytest

_BOTH = {"test_raycast", "test_raycast_batch", "test_lidar_reference"}


def pytest_generate_tests(metafunc):
    if metafunc.module.__name__.rsplit(".", 1)[-1] in _BOTH:
        metafunc.parametrize("tracer", ["numba", "numpy"], indirect=True)


@pytest.fixture(autouse=True)
def tracer(request, monkeypatch):
    """Which tracer RayCaster uses (through PYMUNK_BOT_NUMBA): both in the caster's own
    tests, the default elsewhere."""
    choice = getattr(request, "param", "default")
    if choice != "default":
        monkeypatch.setenv("PYMUNK_BOT_NUMBA", "1" if choice == "numba" else "0")
    return choice
