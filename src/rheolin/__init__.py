"""rheolin: periodic steady state and stability of rotating transmissions.

Linearized equations with time-periodic ("rheo-linear") coefficients,
``M(t) q'' + D(t) q' + K(t) q = f(t)``, solved by harmonic balance in the frequency domain.

>>> import rheolin as rl
>>> sorted(rl.METHODS)
['direct', 'gmres', 'lti', 'perturbation', 'transient']
"""

import logging

from .errors import ModelError
from .floquet import FloquetResult, floquet
from .harmonics.sets import HarmonicSet, TruncationWarning
from .mechanics import Assembled, Model
from .mechanics.preload import OperatingPoint, operating_point
from .solvers import METHODS, solve
from .solvers.solution import STATUS, Solution
from .system.periodic import PeriodicSystem

__all__ = [
    "METHODS",
    "STATUS",
    "Assembled",
    "FloquetResult",
    "HarmonicSet",
    "Model",
    "ModelError",
    "OperatingPoint",
    "PeriodicSystem",
    "Solution",
    "TruncationWarning",
    "floquet",
    "operating_point",
    "solve",
]

__version__ = "0.1.0"

logging.getLogger(__name__).addHandler(logging.NullHandler())
