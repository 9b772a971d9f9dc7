"""Maps: occupancy grids (ROS map_server convention), map files, and geometry built from them."""
from .grid import OccupancyGrid

__all__ = ["OccupancyGrid"]
