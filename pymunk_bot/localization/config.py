"""Moved to :mod:`pymunk_bot.config.localization` (the localizers' and mapping's sections are
part of the scenario format); this path keeps working."""
from pymunk_bot.config.localization import (LOCALIZER_MAP_RESOLUTION, MAX_MAP_CELLS,
                                            MAX_PARTICLES_LIMIT, EkfConfig, MappingConfig,
                                            MclConfig, SlamConfig)

__all__ = ["LOCALIZER_MAP_RESOLUTION", "MAX_MAP_CELLS", "MAX_PARTICLES_LIMIT", "EkfConfig",
           "MappingConfig", "MclConfig", "SlamConfig"]
