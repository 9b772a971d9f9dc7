"""ROS 2 tests need the optional packages of `pip install 'pymunk-bot[ros2]'` (and roslibpy,
a dev dependency, as the real rosbridge client)."""
from __future__ import annotations

import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")
