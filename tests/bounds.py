"""Bounds that hold on a busy machine (issue 35).

A test bounds what it costs in CPU time, which load does not change, and guards against a hang
with a wall-clock limit far above any honest run: on 2 cores at load 8 a program gets about a
quarter of a core, so a 10 s subprocess may take 40-60 s of wall time and still be correct.
"""
from __future__ import annotations

import resource

HANG_GUARD = 600.0  # [s] of wall time: only a hang (or a machine stalled for minutes) reaches it


def children_cpu() -> float:
    """CPU time [s] (user + system) used so far by this process's finished children: the
    difference across ``subprocess.run`` is what that child cost, whatever the load."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime
