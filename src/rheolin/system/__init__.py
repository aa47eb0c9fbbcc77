"""The periodic system: the one interface between mechanics and solvers.

1. A system holds the Fourier coefficients of ``M(t) q'' + D(t) q' + K(t) q = f(t)`` over
   its base frequency ``w1`` (negative harmonics are filled in as complex conjugates):

   >>> import numpy as np
   >>> from rheolin.system import PeriodicSystem
   >>> s = PeriodicSystem(1.0, M={0: np.eye(2)}, K={0: np.diag([1.0, 0.0])},
   ...                    f={1: np.array([0.5, 0.0])})
   >>> s.n, s.coefficient_harmonics, s.load_harmonics
   (2, [], [-1, 1])

2. Exact constraints between DOFs (a rigid link) reduce it to fewer DOFs:

   >>> from rheolin.system import LinearConstraint
   >>> tie = LinearConstraint(pivots=np.array([1]), keep=np.array([0]), G=np.eye(1), n=2)
   >>> tie.reduce(s).n
   1

3. A rigid-body mode (a null vector of ``K_0`` that carries mass) is found, and held by the
   solvers and the stability check:

   >>> from rheolin.system import find_rigid_modes
   >>> find_rigid_modes(s).count
   1

4. A system is not changed once built, so what the analyses derive from it is made once and
   kept on it: the coefficient blocks that the solvers and the stability check share.

   >>> from rheolin.harmonics.blocks import coefficient_blocks
   >>> s.kept("coefficient_blocks") is None
   True
   >>> list(coefficient_blocks(s)), list(s.kept("coefficient_blocks"))
   ([0], [0])
"""

from .constraints import LinearConstraint
from .periodic import PeriodicSystem
from .reduction import Reduction, craig_bampton
from .rigid_modes import RigidModes, find_rigid_modes

__all__ = [
    "LinearConstraint",
    "PeriodicSystem",
    "Reduction",
    "RigidModes",
    "craig_bampton",
    "find_rigid_modes",
]
