"""Maps: occupancy grids (ROS map_server convention), map files, and geometry built from them."""
from pymunk_bot.maps.grid import OccupancyGrid

# The kinds of world `pymunk-bot generate` makes (maps/generate.py): here, so the command line
# can offer them without loading the generator and its planner.
WORLD_KINDS = ("maze", "clutter", "office")

__all__ = ["OccupancyGrid", "MapGeometry", "add_to_space", "free_disc", "geometry_from_grid",
           "load_world_map", "read_ros_map", "read_svg_map", "write_ros_map"]


def __getattr__(name: str):
    # Lazy: the planner imports maps.grid, and maps.geometry imports the planner's helpers.
    if name in ("MapGeometry", "add_to_space", "free_disc", "geometry_from_grid"):
        from pymunk_bot.maps import outlines as geometry
        return getattr(geometry, name)
    if name in ("read_ros_map", "write_ros_map"):
        from pymunk_bot.maps import ros
        return getattr(ros, name)
    if name == "read_svg_map":
        from pymunk_bot.maps.svg import read_svg_map
        return read_svg_map
    if name == "load_world_map":
        from pymunk_bot.maps.files import load_world_map
        return load_world_map
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
