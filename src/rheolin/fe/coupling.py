"""Interface couplings: FE node sets tied to rheolin 6-DOF nodes.

A coupling ties the DOFs of a set of FE nodes to one *reference node* (6 DOFs: translation and
small rotation in global axes) at a point, usually a bearing centre:

* ``"average"`` (RBE3-like, the default): the reference node moves as the weighted
  least-squares rigid fit of the set's translations, ``q = W u_S`` with ``W R = I`` (a rigid
  motion of the set is reproduced exactly), and a force on it is spread over the set as
  ``W^T F``. It adds no stiffness: the bearing seat deforms as the FE model says. Use it for
  bearing seats in housings and other flexible seats, where a rigid ring would stiffen the
  structure (the usual practice).
* ``"rigid"`` (RBE2-like): every node of the set follows the reference node rigidly,
  ``u_i = u + phi x (x_i - x_ref)`` (and ``phi_i = phi`` for FE rotations). Use it where the
  connected part really is stiff over the set (a shrink-fitted ring, a bolted flange) or for
  a few nodes.

Both become one linear map ``u = T [q; v]`` from the reference DOFs ``q`` and the remaining
FE DOFs ``v`` (:func:`coupling_transform`): a rigid coupling makes its set's DOFs dependent on
``q``; an averaging one makes six well-conditioned DOFs of its set dependent on ``q`` and the
set's other DOFs (column-pivoted QR of ``W`` chooses them).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import ModelError
from ..mechanics.rotation import skew
from .matrices import FEModel

__all__ = ["Coupling", "coupling_transform", "rigid_map"]

KINDS = ("average", "rigid")


@dataclass(frozen=True)
class Coupling:
    """One interface: FE nodes (indices into ``FEModel.coordinates``) tied to a reference
    node at ``reference`` [m].

    Parameters
    ----------
    name
        Interface name (e.g. the bearing's).
    nodes
        FE node indices of the set (use ``FEModel.node_index`` for FE node numbers).
    reference
        Position of the rheolin node.
    kind
        ``"average"`` (RBE3-like) or ``"rigid"`` (RBE2-like); see the module.
    weights
        Per-node weights of the average (default 1).
    """

    name: str
    nodes: Sequence[int] | np.ndarray
    reference: Sequence[float] | np.ndarray
    kind: str = "average"
    weights: Sequence[float] | np.ndarray | None = None


def rigid_map(points: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``R`` (``3k x 6``): translations of ``k`` points moving rigidly with a reference node,
    ``u_i = u + phi x r_i = [I, -[r_i]x] q``.

    >>> rigid_map(np.array([[1.0, 0, 0]]), np.zeros(3)) @ [0, 0, 0, 0, 0, 1.0]
    array([0., 1., 0.])
    """
    r = np.asarray(points, float) - np.asarray(reference, float)
    out = np.zeros((3 * len(r), 6))
    for i, ri in enumerate(r):
        out[3 * i : 3 * i + 3, :3] = np.eye(3)
        out[3 * i : 3 * i + 3, 3:] = -skew(ri)
    return out


def _check(fe: FEModel, c: Coupling, where: str) -> tuple[np.ndarray, np.ndarray]:
    if c.kind not in KINDS:
        raise ModelError(f"{where}.kind: must be one of {list(KINDS)}, got {c.kind!r}")
    nodes = np.unique(np.asarray(c.nodes, dtype=np.int64).ravel())
    if nodes.size == 0:
        raise ModelError(f"{where}.nodes: the node set is empty")
    if nodes.min() < 0 or nodes.max() >= fe.coordinates.shape[0]:
        raise ModelError(f"{where}.nodes: node indices outside the FE model")
    ref = np.asarray(c.reference, dtype=float).ravel()
    if ref.shape != (3,) or not np.all(np.isfinite(ref)):
        raise ModelError(f"{where}.reference: must be a finite 3-vector [m]")
    return nodes, ref


def _average(fe: FEModel, c: Coupling, nodes: np.ndarray, ref: np.ndarray, where: str):  # type: ignore[no-untyped-def]
    """``W`` (6 x set DOFs) of the weighted least-squares rigid fit and the set's DOFs."""
    dofs = fe.dofs_of(nodes, components=(0, 1, 2))
    if dofs.size != 3 * nodes.size:
        raise ModelError(f"{where}.nodes: every node of an averaging set needs ux, uy, uz")
    w = np.ones(nodes.size) if c.weights is None else np.asarray(c.weights, dtype=float)
    if w.shape != (nodes.size,) or np.any(w <= 0):
        raise ModelError(f"{where}.weights: one positive weight per node ({nodes.size})")
    R = rigid_map(fe.coordinates[nodes], ref)
    Wd = np.repeat(w, 3)
    normal = R.T @ (Wd[:, None] * R)
    ev = np.linalg.eigvalsh(normal)
    if ev.min() <= 1e-10 * ev.max():
        raise ModelError(
            f"{where}.nodes: the set cannot carry a rotation about every axis (its "
            f"{nodes.size} nodes are collinear or too few); add nodes or use kind='rigid'"
        )
    W = np.linalg.solve(normal, R.T * Wd[None, :])  # (6, 3k), W R = I
    return W, dofs


def coupling_transform(
    fe: FEModel, couplings: Sequence[Coupling]
) -> tuple[sp.csr_array, np.ndarray]:
    """``T`` with ``u = T [q; v]``: ``q`` the 6 DOFs of each coupling's reference node (in
    order), ``v`` the FE DOFs left independent (returned, as FE DOF indices).

    >>> fe = FEModel.solid(np.eye(6), np.eye(6), np.array([[0.0, 0, 0], [1.0, 0, 0]]))
    >>> T, free = coupling_transform(fe, [Coupling("a", [0], [0, 0, 0], kind="rigid")])
    >>> T.shape, free.tolist()
    ((6, 9), [3, 4, 5])
    """
    n = fe.n_dof
    dependent: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # fe dof -> (q coeffs, v dofs)
    rows_q: list[tuple[int, int, float]] = []  # (fe dof, q index, value)
    rows_v: list[tuple[int, int, float]] = []  # (fe dof, fe dof of v, value)
    used = np.zeros(n, dtype=bool)
    for j, c in enumerate(couplings):
        where = f"interface[{j}] ({c.name!r})"
        nodes, ref = _check(fe, c, where)
        q0 = 6 * j
        if c.kind == "rigid":
            for node in nodes:
                Rn = rigid_map(fe.coordinates[[node]], ref)
                for d in fe.dofs_of([node]):
                    if used[d]:
                        raise ModelError(f"{where}.nodes: FE node shared with another interface")
                    used[d] = True
                    comp = int(fe.dof_component[d])
                    coeff = Rn[comp] if comp < 3 else np.eye(6)[comp]
                    rows_q += [(int(d), q0 + k, float(v)) for k, v in enumerate(coeff) if v]
        else:
            W, dofs = _average(fe, c, nodes, ref, where)
            if used[dofs].any():
                raise ModelError(f"{where}.nodes: FE node shared with another interface")
            _, _, piv = sla.qr(W, pivoting=True, mode="economic")
            m = piv[:6]  # dependent DOFs of the set (columns of W best conditioned)
            s = np.setdiff1d(np.arange(dofs.size), m)
            Wm_inv = np.linalg.inv(W[:, m])
            from_q = Wm_inv  # u_m = Wm^-1 q - Wm^-1 Ws u_s
            from_s = -Wm_inv @ W[:, s]
            used[dofs[m]] = True
            for a, d in enumerate(dofs[m]):
                rows_q += [(int(d), q0 + k, float(v)) for k, v in enumerate(from_q[a]) if v]
                rows_v += [(int(d), int(dofs[s][b]), float(v)) for b, v in enumerate(from_s[a])]
    free = np.flatnonzero(~used)
    col_of = np.full(n, -1, dtype=np.int64)
    col_of[free] = 6 * len(couplings) + np.arange(free.size)
    r = [d for d, _, _ in rows_q] + [d for d, _, _ in rows_v] + free.tolist()
    cidx = (
        [k for _, k, _ in rows_q] + [int(col_of[vd]) for _, vd, _ in rows_v] + col_of[free].tolist()
    )
    vals = [v for _, _, v in rows_q] + [v for _, _, v in rows_v] + [1.0] * free.size
    if rows_v and min(col_of[vd] for _, vd, _ in rows_v) < 0:
        raise ModelError("interfaces: an averaging set depends on another interface's DOFs")
    T = sp.csr_array((vals, (r, cidx)), shape=(n, 6 * len(couplings) + free.size))
    del dependent
    return T, free
