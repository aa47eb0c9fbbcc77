"""Stability maps and Campbell diagrams of rotating, time-periodic systems (docs/stability.md).

* :func:`campbell`: natural frequencies, damping and whirl of the time-averaged system against
  speed, order lines and their crossings (critical speeds).
* :func:`stability_map`: the largest Floquet real part of the full periodic system against
  speed, unstable ranges with bounds and mechanism.

>>> from rheolin.stability import campbell, stability_map
>>> callable(campbell) and callable(stability_map)
True
"""

from .campbell import CampbellResult, CriticalSpeed, campbell, order_lines
from .mechanism import Mechanism, identify
from .modes import AveragedModes, averaged_modes, whirl_ratio
from .stability_map import (
    StabilityMap,
    UnstableRange,
    map_from_results,
    mechanism,
    stability_map,
)

__all__ = [
    "AveragedModes",
    "CampbellResult",
    "CriticalSpeed",
    "Mechanism",
    "StabilityMap",
    "UnstableRange",
    "averaged_modes",
    "campbell",
    "identify",
    "map_from_results",
    "mechanism",
    "order_lines",
    "stability_map",
    "whirl_ratio",
]
