"""The preloaded operating point: the static equilibrium under torque, gravity and mean loads,
and the linearized model about it (docs/preload.md).

1. :func:`operating_point` (:mod:`.equilibrium`) finds the static equilibrium of a model's
   load-dependent joints and torques;
2. the result, an :class:`OperatingPoint` (:mod:`.state`), holds each bearing's and mesh's
   state and the model linearized there (:mod:`.linearize`), which every solver uses;
3. :func:`preloaded_template` gives the speed template of a preloaded model.

>>> import rheolin as rl
>>> m = rl.Model()
>>> m.add_rigid_body("r", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
>>> m.add_bearing("axial", "r", 0, stiffness=[1e8, 1e4, 1e4, 1e4],
...               components=["uz", "phix", "phiy", "phiz"])
>>> m.add_rolling_bearing("A", "r", 0, law="radial", kind="ball", stiffness=2e10)
>>> m.add_force("w", "r", 0, force=(0.0, -100.0, 0.0))
>>> op = operating_point(m, 1.0)
>>> round(op.bearings["A"].load, 6), op.model.preloaded
(100.0, False)
"""

from .equilibrium import operating_point
from .linearize import preloaded_template
from .state import BearingState, MeshState, OperatingPoint

__all__ = ["BearingState", "MeshState", "OperatingPoint", "operating_point", "preloaded_template"]
