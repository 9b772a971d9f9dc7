"""Batch ray casting that returns what pymunk's ``Space.segment_query_first`` returns.

How it stays exact: every (primitive, ray) test repeats Chipmunk's own floating-point
expressions in Chipmunk's order (cpPolyShapeSegmentQuery, CircleSegmentQuery,
cpSegmentShapeSegmentQuery) on world geometry built with Chipmunk's transform arithmetic,
so each candidate alpha is bit-identical to pymunk's, and the answer per ray is their
minimum, as in cpSpaceSegmentQueryFirst. The start-inside rule (alpha 0 when the point
query at the origin gives distance <= 0) is asked of pymunk itself, and a cast whose
origin is within rounding of a shape's boundary is left to pymunk. pymunk also skips a
static shape whose bounding box a rounded slab test says the segment misses (moving
shapes sit in boxes padded by 10%, so only static ones matter); that can differ from the
shape test only for rays running (within rounding) along a box side or through a box
corner lying on the shape, so such rays are detected with wide margins and answered by
pymunk directly. Everything else only chooses which pairs to test, always
with margins far above rounding, so the choice never changes a result.

How it is fast: shapes the filter rejects are dropped, back-facing polygon edges are
dropped by Chipmunk's own plane test, shapes out of range by their bounding circles, and
each primitive meets only the rays inside the angle it subtends (the rays are sorted by
angle, so that is an index range); once every ray of a cast has hit something, the compiled
tracer passes over primitives whose shapes lie beyond its farthest hit, and each ray over
those beyond its own. The loop over primitives and their rays is compiled with
numba (``compiled``); without numba, numpy does the same work in arrays, tracing dense
scenes in rings of growing distance so rays already stopped nearby skip far shapes. Static
geometry is cached in world coordinates; moving bodies are moved once per frame, and a
filter whose visible bodies have not moved keeps the table it had.

Differences from pymunk, by design:
- pymunk queries see a shape where it was at the last ``space.step()`` or reindex; this
  caster uses each body's current transform. They agree whenever a body moved by hand
  has been reindexed (``space.reindex_shapes_for_body``), and always after a step.
- Changing a shape's filter, radius or vertices, or a body's type, without adding or
  removing a shape is not detected: call :meth:`RayCaster.invalidate`.
- Bodies put to sleep (only if the space enables sleeping) are treated as moving bodies,
  so rays grazing their bounding boxes are not handed to pymunk (a measure-zero case; so
  is a moving shape whose box has drifted exactly onto its padded box in pymunk's tree).
- The space is assumed to use its default bounding-box tree, not ``use_spatial_hash``.

Modules (all but this one are internal):
- ``reference``: argument checks, the shared segment end points, and ``reference_cast``.
- ``geometry``: primitive tables (one column per polygon edge, circle, segment) built from
  pymunk shapes with Chipmunk's arithmetic.
- ``cache``: the per-space cache of those tables, bounding-box corner flags, filters.
- ``fan``: the rays of one cast sorted by angle, and angle interval -> ray index range.
- ``scene``: per-cast culling, the angle interval of each primitive, and tracing.
- ``kernels``: the exact per-pair Chipmunk formulas.
- ``compiled``: ``fan``, ``scene`` and ``kernels`` in one numba loop (loaded on first use).
- ``caster``: ``RayCaster``, which ties these together and picks pymunk fallbacks.
- ``spaces``: ``Spaces``, several Spaces cast against as one (a world's robots stepping apart).
"""

from pymunk_bot.sensors.raycast.caster import RayCaster
from pymunk_bot.sensors.raycast.reference import reference_cast
from pymunk_bot.sensors.raycast.spaces import Spaces

__all__ = ["RayCaster", "Spaces", "reference_cast"]
