"""The preloaded operating point: the static equilibrium under torque, gravity and mean loads,
and the linearized model about it (docs/preload.md)."""

from .equilibrium import (
    BearingState,
    MeshState,
    OperatingPoint,
    operating_point,
    preloaded_template,
)

__all__ = ["BearingState", "MeshState", "OperatingPoint", "operating_point", "preloaded_template"]
