"""Exact linear constraints between DOFs, eliminated: ``q[pivots] = G q[keep]``.

A rigid link makes one node's DOFs follow another's (``u_b = u_a + phi_a x r``,
``phi_b = phi_a``); the held rigid-body modes of :mod:`rheolin.system.rigid_modes` are another case.
Either way the constrained DOFs are eliminated: with ``q = T y`` (``T`` the identity on the
kept DOFs and ``G`` on the eliminated ones) the equations are projected, ``T^T X(t) T y`` and
``T^T f(t)``: the constraint forces drop out exactly, no penalty stiffness is involved, and the
answer is expanded back onto every DOF.

>>> import numpy as np, rheolin as rl
>>> c = LinearConstraint(pivots=np.array([1]), keep=np.array([0]), G=np.array([[1.0]]), n=2)
>>> s = rl.PeriodicSystem(1.0, M={0: np.eye(2)}, K={0: np.diag([1.0, 3.0])})
>>> c.reduce(s).K[0]  # two masses moving as one: 2 kg on 4 N/m
array([[4.]])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from .periodic import PeriodicSystem

__all__ = ["LinearConstraint"]


@dataclass
class LinearConstraint:
    """``q[pivots] = G q[keep]`` on a system of ``n`` DOFs (``keep`` sorted, disjoint)."""

    pivots: np.ndarray
    keep: np.ndarray
    G: np.ndarray
    n: int

    def transform(self) -> sp.csr_array:
        """``T`` (``n x len(keep)``) with ``q = T y``."""
        m = self.keep.size
        G = sp.coo_array(np.asarray(self.G))
        rows = np.concatenate([self.keep, self.pivots[G.row]])
        cols = np.concatenate([np.arange(m), G.col])
        vals = np.concatenate([np.ones(m), G.data])
        T = sp.coo_array((vals, (rows, cols)), (self.n, m)).tocsr()
        T.eliminate_zeros()
        return T

    def reduce(self, system: PeriodicSystem) -> PeriodicSystem:
        """The constrained system ``T^T X(t) T``, ``T^T f(t)`` (same format, sparse or dense)."""
        if system.n != self.n:
            raise ValueError(f"the system has {system.n} DOFs, the constraint {self.n}")
        T = self.transform()
        Tt = T.T.tocsr()

        def project(X: Any) -> Any:
            if sp.issparse(X):
                return sp.csc_array(Tt @ sp.csr_array(X) @ T)
            return np.asarray(Tt @ np.asarray(Tt @ np.asarray(X).T).T)

        coeffs = {
            name: {k: project(X) for k, X in getattr(system, name).items()}
            for name in ("M", "D", "K")
        }
        loads = {k: Tt @ np.asarray(v) for k, v in system.f.items()}
        out = PeriodicSystem(system.omega, f=loads, **coeffs)
        motions = getattr(system, "motions", None)
        out.motions = None if motions is None else motions.through(T)
        return out

    def expand(self, Y: np.ndarray) -> np.ndarray:
        """``q = T y`` along the last axis (``(..., len(keep)) -> (..., n)``)."""
        Y = np.asarray(Y)
        out = np.zeros((*Y.shape[:-1], self.n), dtype=np.result_type(Y.dtype, float))
        out[..., self.keep] = Y
        out[..., self.pivots] = Y @ np.asarray(self.G).T
        return out

    def restrict(self, Q: np.ndarray) -> np.ndarray:
        """``y = q[keep]`` (e.g. a warm start of the full system for the constrained one)."""
        return np.asarray(Q)[..., self.keep]
