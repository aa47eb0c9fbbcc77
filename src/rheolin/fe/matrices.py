"""An FE body as matrices: :class:`FEModel` (sparse ``K``, ``M``, optional ``D``, and the map
from matrix rows to FE nodes and their components).

The FE program numbers its nodes freely (``node_ids``); rows of the matrices are DOFs, each
one component (``0..2`` translations ``x, y, z``, ``3..5`` rotations) of one node, in the FE
model's global axes and SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError

__all__ = ["FEModel"]

#: Relative asymmetry above which a mass, stiffness or damping matrix is refused.
SYMMETRY_RTOL = 1e-8


def _sparse(x: Any, name: str, n: int | None) -> sp.csr_array:
    try:
        a = sp.csr_array(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ModelError(f"`{name}` must be a real square matrix: {exc}") from None
    if a.shape[0] != a.shape[1] or (n is not None and a.shape != (n, n)):
        want = "square" if n is None else f"{n}x{n}"
        raise ModelError(f"`{name}` must be {want}, got shape {a.shape}")
    if not np.all(np.isfinite(a.data)):
        raise ModelError(f"`{name}` has non-finite entries")
    a.sum_duplicates()
    scale = float(np.abs(a.data).max(initial=0.0))
    asym = float(abs(a - a.T).max()) if a.nnz else 0.0
    if asym > SYMMETRY_RTOL * scale:
        raise ModelError(
            f"`{name}` must be symmetric (largest |{name} - {name}^T| is {asym:.3g}, "
            f"{asym / scale:.2g} of its largest entry)"
        )
    return sp.csr_array(0.5 * (a + a.T))


@dataclass
class FEModel:
    """Matrices of an FE body and what each row means.

    Parameters
    ----------
    K, M
        Stiffness and mass (symmetric, sparse or dense), ``n x n``.
    coordinates
        Node positions ``(n_nodes, 3)`` [m].
    dof_node
        For each DOF, the index of its node in ``coordinates`` (not the FE id).
    dof_component
        For each DOF, its component ``0..5`` (``ux uy uz phix phiy phiz``).
    node_ids
        The FE program's node numbers (default ``0..n_nodes-1``).
    D
        Viscous damping (symmetric), or None.

    Examples
    --------
    >>> fe = FEModel.solid(np.eye(6), np.eye(6), np.zeros((2, 3)))
    >>> fe.n_dof, fe.dofs_of([1]).tolist()
    (6, [3, 4, 5])
    """

    K: Any
    M: Any
    coordinates: np.ndarray
    dof_node: np.ndarray
    dof_component: np.ndarray
    node_ids: np.ndarray | None = None
    D: Any = None
    _lookup: dict[int, int] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        self.K = _sparse(self.K, "K", None)
        n = self.K.shape[0]
        self.M = _sparse(self.M, "M", n)
        self.D = None if self.D is None else _sparse(self.D, "D", n)
        xyz = np.asarray(self.coordinates, dtype=float)
        if xyz.ndim != 2 or xyz.shape[1] != 3 or not np.all(np.isfinite(xyz)):
            raise ModelError(f"`coordinates` must be finite, shape (n_nodes, 3), got {xyz.shape}")
        self.coordinates = xyz
        node = np.asarray(self.dof_node, dtype=np.int64).ravel()
        comp = np.asarray(self.dof_component, dtype=np.int64).ravel()
        if node.shape != (n,) or comp.shape != (n,):
            raise ModelError(f"`dof_node` and `dof_component` need one entry per DOF ({n})")
        if node.min(initial=0) < 0 or node.max(initial=0) >= xyz.shape[0]:
            raise ModelError("`dof_node` must index `coordinates`")
        if comp.min(initial=0) < 0 or comp.max(initial=0) > 5:
            raise ModelError("`dof_component` must be in 0..5 (ux uy uz phix phiy phiz)")
        keys = node * 6 + comp
        if np.unique(keys).size != n:
            raise ModelError("two DOFs share a node and component")
        self.dof_node, self.dof_component = node, comp
        ids = np.arange(xyz.shape[0]) if self.node_ids is None else np.asarray(self.node_ids)
        if ids.shape != (xyz.shape[0],) or np.unique(ids).size != ids.size:
            raise ModelError("`node_ids` must be distinct, one per row of `coordinates`")
        self.node_ids = ids.astype(np.int64)
        self._lookup = {int(i): j for j, i in enumerate(self.node_ids)}

    @classmethod
    def solid(cls, K: Any, M: Any, coordinates: np.ndarray, D: Any = None) -> FEModel:
        """Translational DOFs only, ``3 i + c`` for component ``c`` of node ``i``."""
        n_nodes = np.asarray(coordinates).shape[0]
        return cls(
            K,
            M,
            coordinates,
            np.repeat(np.arange(n_nodes), 3),
            np.tile(np.arange(3), n_nodes),
            D=D,
        )

    @property
    def n_dof(self) -> int:
        """Number of DOFs (rows)."""
        return int(self.K.shape[0])

    def node_index(self, ids: Any) -> np.ndarray:
        """Row indices into ``coordinates`` of FE node numbers ``ids``."""
        try:
            return np.array([self._lookup[int(i)] for i in np.ravel(ids)], dtype=np.int64)
        except KeyError as exc:
            raise ModelError(f"FE node {exc.args[0]} does not exist in the model") from None

    def dofs_of(self, nodes: Any, components: Any = None) -> np.ndarray:
        """DOF indices of the nodes (indices into ``coordinates``), optionally only some
        components, ordered by node then component."""
        nodes = np.asarray(nodes, dtype=np.int64).ravel()
        want = np.isin(self.dof_node, nodes)
        if components is not None:
            want &= np.isin(self.dof_component, np.asarray(components))
        idx = np.flatnonzero(want)
        rank = np.searchsorted(np.sort(nodes), self.dof_node[idx])
        return idx[np.lexsort((self.dof_component[idx], rank))]

    def nodes_where(self, mask_fn: Any) -> np.ndarray:
        """Node indices whose coordinates satisfy ``mask_fn(xyz) -> bool array``."""
        return np.flatnonzero(np.asarray(mask_fn(self.coordinates), dtype=bool))
