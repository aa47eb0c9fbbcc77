"""Harmonic sets, harmonic lattices and the harmonic-balance operator.

1. A harmonic set grows from the load harmonics by the coefficient harmonics (a closure), so a
   system whose time variation has few frequencies keeps few harmonics:

   >>> import numpy as np
   >>> from rheolin.system import PeriodicSystem
   >>> from rheolin.harmonics import HarmonicSet
   >>> s = PeriodicSystem(0.5, M={0: np.eye(1)}, D={0: 0.1 * np.eye(1)},
   ...                    K={0: np.eye(1), 2: 0.1 * np.eye(1)}, f={1: np.ones(1)})
   >>> HarmonicSet.closure(s, order=2).indices
   array([-5, -3, -1,  1,  3,  5])

2. The lattice of a system is the same idea around harmonic 0, for Hill's method
   (stability): integer combinations of the coefficient harmonics within a cost:

   >>> from rheolin.harmonics import system_lattice
   >>> system_lattice(s, 1).indices.tolist()
   [-2, 0, 2]

3. The harmonic-balance operator applies ``sum_n A_{m-n}(n) q_n`` and solves its
   time-averaged blocks ``A0(n)``. Left alone, ``A0`` misses the coupling through ``K_2``;
   :func:`rheolin.solve` iterates on it (GMRES preconditioned by ``A0^-1``):

   >>> from rheolin.harmonics import HarmonicBalance
   >>> H = HarmonicSet.closure(s, order=2)
   >>> op = HarmonicBalance(s, H)
   >>> round(op.relative_residual(op.solve_A0(op.rhs)), 3)
   0.188
   >>> import rheolin as rl
   >>> bool(op.relative_residual(op.half(rl.solve(s, H).q)) < 1e-12)
   True
"""

from .balance import HarmonicBalance, SingularBlockError
from .hill import hill_pencil, state_scaling
from .hill_lattice import LatticeHill
from .lattice import Lattice, harmonic_lattice, system_lattice
from .sets import HarmonicSet, TruncationWarning, as_harmonic_set

__all__ = [
    "HarmonicBalance",
    "HarmonicSet",
    "Lattice",
    "LatticeHill",
    "SingularBlockError",
    "TruncationWarning",
    "as_harmonic_set",
    "harmonic_lattice",
    "hill_pencil",
    "state_scaling",
    "system_lattice",
]
