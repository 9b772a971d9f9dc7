"""The engine: a scenario built into a run, and the batch that ticks runs sharing a Space.

``build`` (config + seed -> world, robots, sensors, controllers), ``simulation`` (a run: its
clock, phases and results; a batch of one), ``batch`` (the one place where the tick order
lives), ``replicas`` and ``stacking`` (copies of one scenario in one Space), ``events``
(things that happen at a simulated time), ``observing`` (what controllers see).
"""
