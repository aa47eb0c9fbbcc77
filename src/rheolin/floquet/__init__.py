"""Floquet stability of the periodic system by Hill's method (docs/stability.md, docs/stability.md).

Three paths over the same (balanced) Hill pencil ``lambda B y = A y``:

* ``"dense"``: every eigenvalue by QZ, with left eigenvectors for a per-exponent error bound;
* ``"sparse"``: only the exponents near the imaginary axis, by shift-invert Arnoldi
  (``scipy.sparse.linalg.eigs`` on ``(A - sigma B)^-1 B``, one sparse LU per shift) along a
  frequency range; the adjoint problem gives the left eigenvectors for the same error bound;
* ``"lattice"``: for systems whose time variation comes from a few generators (gear meshes,
  shafts), the Hill problem on the lattice of their integer combinations, solved near every
  mode of the time-averaged system (modules ``search``, ``shift_invert``, ``select``,
  ``representatives``, ``checks``, ``confirm``).

The dense and sparse paths need a dense grid ``-N..N`` (in units of the gcd of its indices);
any other harmonic set is refused, because their choice of representatives and their
truncation test assume one.

Representatives are the copies whose eigenvector is centred on harmonic 0 (smallest
energy-weighted mean of ``|n|``; the signed mean would also pick spurious eigenvectors split
between the two ends of the truncation), folded into ``(-w1/2, w1/2]`` by the dense and sparse
paths; the lattice path keeps the centred copy.

Modules: ``api`` (the entry point and its choice of truncation), ``result`` (the result and its
verdict), ``dense``, ``sparse`` and ``common`` (the grid paths), and for the lattice ``averaged``
(the modes it starts from and their Gershgorin discs), ``search`` (the search and its memory),
``shift_invert`` (its factors, Arnoldi and polish), ``select`` (one representative per
exponent), ``representatives`` (their bounds and truncation estimates), ``checks``,
``confirm``, ``continuation`` (over a sweep) and ``outcome``; ``reduced``: the verdict on a
Craig-Bampton reduction of a large system (:mod:`rheolin.system.reduction`).
"""

from ..harmonics.hill import hill_matrices, hill_pencil
from .api import (
    AUTO_DENSE_LIMIT,
    DEFAULT_LATTICE_ORDER,
    MAX_DENSE_HILL,
    dense_stability_harmonics,
    floquet,
    floquet_memory,
)
from .averaged import MAX_AVERAGED_DENSE
from .checks import liouville_sum
from .continuation import Continuation
from .footprint import lattice_memory
from .outcome import LatticeExponents
from .reduced import floquet_reduced
from .result import SAFETY, SPLIT_FACTOR, TRUNCATION_SAFETY, FloquetResult
from .search import lattice_exponents

__all__ = [
    "AUTO_DENSE_LIMIT",
    "DEFAULT_LATTICE_ORDER",
    "MAX_AVERAGED_DENSE",
    "MAX_DENSE_HILL",
    "SAFETY",
    "SPLIT_FACTOR",
    "TRUNCATION_SAFETY",
    "Continuation",
    "FloquetResult",
    "LatticeExponents",
    "dense_stability_harmonics",
    "floquet",
    "floquet_memory",
    "floquet_reduced",
    "hill_matrices",
    "hill_pencil",
    "lattice_exponents",
    "lattice_memory",
    "liouville_sum",
]
