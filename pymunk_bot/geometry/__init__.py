"""Plane geometry without pymunk: polygons and distances (shapely), robot footprints, and
motion along circular arcs (compiled)."""
