"""Sparse assembly of element :class:`~rheolin.mechanics._term.Term` objects.

Each term holds small dense Fourier coefficients on its global DOFs; assembly collects COO
triplets per (matrix, harmonic) and returns SciPy CSR matrices. Never dense ``N x N``.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from ..system.periodic import PeriodicSystem
from ._term import Term
from .speeds import SpeedPlan

__all__ = ["Assembled", "assemble_coefficients", "assemble_system"]

_Coefficients = tuple[
    dict[int, sp.csr_array], dict[int, sp.csr_array], dict[int, sp.csr_array], dict[int, np.ndarray]
]


def assemble_coefficients(terms: Iterable[Term], n_dof: int) -> _Coefficients:
    """Sum terms into sparse ``M_k, D_k, K_k`` and dense ``f_k`` on ``n_dof`` global DOFs.

    Returns
    -------
    (M, D, K, f)
        Dicts from harmonic index to ``csr_array`` (``n_dof x n_dof``) or vector. Harmonic 0 is
        real; for ``k != 0`` both signs are returned as they were given by the terms.

    Examples
    --------
    >>> import numpy as np
    >>> spring = Term(np.array([0, 1]), K={0: np.array([[1.0, -1.0], [-1.0, 1.0]])})
    >>> M, D, K, f = assemble_coefficients([spring, Term(np.array([1]), K={0: np.eye(1)})], 2)
    >>> K[0].toarray()
    array([[ 1., -1.],
           [-1.,  2.]])
    """
    triplets: dict[str, dict[int, tuple[list, list, list]]] = {"M": {}, "D": {}, "K": {}}
    loads: dict[int, np.ndarray] = {}
    for term in terms:
        dofs = np.asarray(term.dofs, dtype=np.int64).ravel()
        d = dofs.size
        if d and (dofs.min() < 0 or dofs.max() >= n_dof):
            raise ModelError(f"term DOF indices must lie in [0, {n_dof}), got {dofs}")
        rows = np.repeat(dofs, d)
        cols = np.tile(dofs, d)
        for name in ("M", "D", "K"):
            for k, x in getattr(term, name).items():
                x = np.asarray(x)
                if x.shape != (d, d):
                    raise ModelError(
                        f"term `{name}[{k}]` must have shape ({d}, {d}), got {x.shape}"
                    )
                r, c, v = triplets[name].setdefault(int(k), ([], [], []))
                r.append(rows)
                c.append(cols)
                v.append(x.ravel())
        for k, vec in term.f.items():
            fk = np.asarray(vec).ravel()
            if fk.shape != (d,):
                raise ModelError(f"term `f[{k}]` must have shape ({d},), got {fk.shape}")
            out = loads.setdefault(int(k), np.zeros(n_dof, dtype=complex))
            np.add.at(out, dofs, fk)
    mats = []
    for name in ("M", "D", "K"):
        table: dict[int, sp.csr_array] = {}
        for k, (r, c, v) in sorted(triplets[name].items()):
            data = np.concatenate(v)
            data = data.real.astype(float) if k == 0 else data.astype(complex)
            mat = sp.coo_array(
                (data, (np.concatenate(r), np.concatenate(c))), shape=(n_dof, n_dof)
            ).tocsr()
            mat.sum_duplicates()
            mat.eliminate_zeros()
            if mat.nnz:
                table[k] = mat
        mats.append(table)
    f = {k: (v.real.copy() if k == 0 else v) for k, v in sorted(loads.items()) if np.any(v != 0)}
    return mats[0], mats[1], mats[2], f


def assemble_system(terms: Iterable[Term], n_dof: int, omega: float) -> PeriodicSystem:
    """Assemble terms into a :class:`~rheolin.PeriodicSystem` with base frequency ``omega``.

    Examples
    --------
    >>> import numpy as np
    >>> s = assemble_system([Term(np.array([0]), M={0: np.eye(1)}, K={0: np.eye(1)},
    ...                           f={1: np.array([0.5]), -1: np.array([0.5])})], 1, 2.0)
    >>> s.n, s.load_harmonics
    (1, [-1, 1])
    """
    M, D, K, f = assemble_coefficients(terms, n_dof)
    return PeriodicSystem(omega=omega, M=M, D=D, K=K, f=f)


@dataclass
class Assembled:
    """A model assembled at one input speed (returned by ``Model.assemble``).

    Attributes
    ----------
    system
        The :class:`~rheolin.PeriodicSystem` (sparse coefficients).
    omega
        Base frequency ``w1`` [rad/s]; ``base_ratio`` is ``w1 / speed`` exactly.
    base_ratio
        ``w1 / speed`` as a Fraction.
    speed
        Input speed [rad/s].
    plan
        Speeds and integer harmonics (:class:`~rheolin.mechanics.speeds.SpeedPlan`).
    generators
        Harmonic generators for :meth:`rheolin.HarmonicSet.closure` (shaft, mesh, load).
    dof_labels
        ``(body, node, component)`` for every global DOF.
    node_index
        ``{(body, node): global node}``.
    joints
        ``{name: Term}`` of bearings and couplings.
    meshes
        ``{name: (Term, w, mesh harmonic)}`` of gear meshes (``delta = w^T q``; ``w`` a
        series ``{k: w_k}`` where it turns: planetary meshes, meshes on a body in a carrier's
        frame).
    frames
        The planetary sets' carrier frames
        (:class:`~rheolin.mechanics.planetary_assembly.Frames`), or None.
    """

    system: PeriodicSystem
    omega: float
    base_ratio: Fraction
    speed: float
    plan: SpeedPlan
    generators: list[int]
    dof_labels: list[tuple[str, int, str]]
    node_index: dict[tuple[str, int], int]
    joints: dict[str, Term]
    meshes: dict[str, tuple[Term, Any, int]]
    frames: Any = None

    def dofs(self, body: str, node: int) -> np.ndarray:
        """The six global DOFs of a node."""
        return 6 * self.node_index[(body, node)] + np.arange(6)
