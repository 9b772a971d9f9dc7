"""The physical world: pymunk settings, the Space with its obstacles and robot bodies, the
steering of control bodies (the tank pattern), and how many substeps each tick takes.

``settings`` (SI settings, collision types), ``world``, ``obstacles``, ``propulsion`` and
``steering`` (twists -> control-body velocities), ``bodies`` (bodies read and written as rows),
``substeps`` (substeps only where contacts can start), ``apart`` (robots nothing can reach step
in a Space of their own).
"""
