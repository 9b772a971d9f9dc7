"""Robots: the handles users hold, the fleet's bookkeeping, commands, readings and drives.

``robot`` (Robot, Fleet), ``progress`` (path length and goals, compiled), ``command``,
``readings`` (what a controller knows at one instant), ``drives/`` (diff, ackermann, omni).
"""
