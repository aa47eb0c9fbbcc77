"""Mechanics: rotating bodies, joints, gears, loads and the Model that assembles them.

>>> from rheolin.mechanics import Model
>>> Model().bodies
{}
"""

from .assembly import Assembled, assemble_coefficients, assemble_system
from .model import Model
from .speeds import GearPair, SpeedPlan, propagate_speeds, rational_gcd, speed_plan

__all__ = [
    "Assembled",
    "GearPair",
    "Model",
    "SpeedPlan",
    "assemble_coefficients",
    "assemble_system",
    "propagate_speeds",
    "rational_gcd",
    "speed_plan",
]
