"""Imported (condensed) bodies: ``M_B, K_B`` (+ optional ``D_B``, gyroscopic ``G_B``) in body axes.

The body's DOFs are node-major, 6 per node ``(u, phi)`` in body axes; ``nodes`` maps body node
``i`` to the global node ``nodes[i]``. ``frame`` holds the body axes in global coordinates (as
columns) at ``t = 0``. The body spins at ``W = s * w1`` about ``axis`` (global); its nodes must
lie on the spin axis (their reference positions do not move). Contributions
(docs/rotating-bodies.md)::

    M += Rt M_B Rt^T,   D += Rt D_B Rt^T + W Rt G_B Rt^T,   K += Rt K_B Rt^T + Rt D_B Rt'^T

``G_B`` is the gyroscopic matrix per unit spin speed about ``+axis``. Inertia terms of a
non-axisymmetric rotary inertia beyond ``G_B`` (the ``J'`` rows of a rigid node) are not
generated; model such inertia with :class:`~rheolin.mechanics.rigid.RigidNode`.

Craig-Bampton bodies (:func:`rheolin.fe.condense`) add ``n_modes`` modal DOFs after the node
DOFs (global indices ``modal_dofs``). Modal amplitudes are body-frame scalars, so ``Rx`` rotates
the nodes' 3-vectors and leaves them alone. Such a body spins with its exact body-frame
inertia (``G_B`` the Coriolis matrix per unit speed, ``C_B`` the centrifugal matrix per unit
speed squared, both from the FE mass): with ``x_B = Rx^T x`` the body-frame equations
``M x_B'' + (D + W G) x_B' + (K + W^2 C) x_B = f_B`` become

    M += Rx M_B Rx^T,
    D += Rx D_B Rx^T + 2 Rx M_B Rx'^T + W Rx G_B Rx^T,
    K += Rx K_B Rx^T + Rx D_B Rx'^T + Rx M_B Rx''^T + W Rx G_B Rx'^T + W^2 Rx C_B Rx^T

(for a body of translational masses the Coriolis and ``Rx'`` terms cancel, as for beams).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy.io
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import ModelError
from ._term import SpeedTerm, Term
from .rotation import (
    add_series,
    circulatory_matrix,
    clean_series,
    derivative,
    rotate_body_matrix,
    rotation_series,
    unit_axis,
)

__all__ = ["CondensedBody", "condensed_body", "load_condensed", "load_matrix"]


def load_matrix(path: str | Path) -> np.ndarray:
    """Dense matrix from a Matrix Market (``.mtx``) or NumPy (``.npy``) file.

    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "k.mtx")
    >>> scipy.io.mmwrite(p, np.eye(2))
    >>> load_matrix(p)
    array([[1., 0.], [0., 1.]])
    """
    p = Path(path)
    if p.suffix == ".mtx" or p.name.endswith(".mtx.gz"):
        a = scipy.io.mmread(str(p))
    elif p.suffix == ".npy":
        a = np.load(p)
    else:
        raise ModelError(f"`path` must be a .mtx, .mtx.gz or .npy file, got {str(p)!r}")
    a = a.toarray() if sp.issparse(a) else np.asarray(a)
    return np.asarray(a, dtype=float)


#: Relative tolerance of the symmetry and (semi-)definiteness checks of condensed matrices.
DEFINITE_RTOL = 1e-9

_MATRIX_NAME = {"M": "mass", "K": "stiffness", "D": "damping"}


def _check_semidefinite(name: str, x: np.ndarray) -> None:
    """Refuse a condensed mass, stiffness or damping matrix that is not symmetric positive
    semidefinite (to :data:`DEFINITE_RTOL` of its largest entry); the mass must also have a
    positive diagonal somewhere (not all zero)."""
    what = f"`{name}` (the {_MATRIX_NAME[name]} matrix)"
    scale = float(np.abs(x).max(initial=0.0))
    if name == "M" and scale == 0.0:
        raise ModelError(f"{what} is zero; a body needs mass")
    if scale == 0.0:
        return
    asym = float(np.abs(x - x.T).max()) / scale
    if asym > 1e-8:
        raise ModelError(f"{what} must be symmetric; largest |A - A^T| / max|A| = {asym:.3g}")
    low = float(sla.eigh(0.5 * (x + x.T), eigvals_only=True, subset_by_index=[0, 0])[0])
    if low < -DEFINITE_RTOL * scale * x.shape[0]:
        raise ModelError(
            f"{what} must be positive semidefinite; its smallest eigenvalue is {low:.4g} "
            f"(largest entry {scale:.4g}); allowed: eigenvalues >= 0"
        )


@dataclass(frozen=True)
class CondensedBody:
    """A body given by condensed matrices in body axes.

    Parameters
    ----------
    M, K
        Mass and stiffness matrices (``6 n x 6 n`` for ``n`` nodes), body axes.
    nodes
        Global node index of each body node.
    D
        Rotating (material) damping matrix, or ``None``.
    G
        Gyroscopic matrix per unit spin speed about ``+axis``, or ``None``.
    frame
        3x3 rotation whose columns are the body axes in global coordinates at ``t = 0``.

    Examples
    --------
    >>> b = CondensedBody(M=np.eye(6), K=2 * np.eye(6), nodes=[4])
    >>> t = b.term([0, 0, 1], 1, 10.0)
    >>> t.dofs.tolist(), sorted(t.K)
    ([24, 25, 26, 27, 28, 29], [0])
    """

    M: np.ndarray
    K: np.ndarray
    nodes: Sequence[int]
    D: np.ndarray | None = None
    G: np.ndarray | None = None
    frame: np.ndarray | None = None
    n_modes: int = 0
    C: np.ndarray | None = None
    modal_dofs: Sequence[int] = ()

    def __post_init__(self) -> None:
        nodes = np.asarray(self.nodes)
        if nodes.ndim != 1 or nodes.size == 0 or not np.issubdtype(nodes.dtype, np.integer):
            raise ModelError(f"`nodes` must be a nonempty list of integers, got {self.nodes!r}")
        if nodes.min() < 0 or len(set(nodes.tolist())) != nodes.size:
            raise ModelError("`nodes` must be distinct nonnegative node indices")
        n = 6 * nodes.size + int(self.n_modes)
        for name in ("M", "K", "D", "G", "C"):
            x = getattr(self, name)
            if x is None:
                continue
            x = x.toarray() if sp.issparse(x) else np.asarray(x, dtype=float)
            if x.shape != (n, n) or not np.all(np.isfinite(x)):
                raise ModelError(
                    f"`{name}` must be a finite {n}x{n} matrix (6 DOFs x {nodes.size} nodes "
                    f"+ {self.n_modes} modes), got shape {x.shape}"
                )
            if name in ("M", "K", "D"):
                _check_semidefinite(name, x)
            object.__setattr__(self, name, x)
        T = np.eye(3) if self.frame is None else np.asarray(self.frame, dtype=float)
        if T.shape != (3, 3) or not np.allclose(T.T @ T, np.eye(3), atol=1e-10):
            raise ModelError("`frame` must be a 3x3 rotation matrix (orthonormal columns)")
        if np.linalg.det(T) < 0:
            raise ModelError("`frame` must be a proper rotation (determinant +1)")
        object.__setattr__(self, "frame", T)
        object.__setattr__(self, "nodes", nodes.astype(np.int64))

    @property
    def dofs(self) -> np.ndarray:
        """Global DOF indices, node-major, then the modal DOFs."""
        nodal = (6 * np.asarray(self.nodes)[:, None] + np.arange(6)).ravel()
        if not self.n_modes:
            return nodal
        modal = np.asarray(self.modal_dofs, dtype=np.int64).ravel()
        if modal.size != self.n_modes:
            raise ModelError(f"`modal_dofs` must hold {self.n_modes} global DOF indices")
        return np.concatenate([nodal, modal])

    def _global(self, x: np.ndarray) -> np.ndarray:
        frame = np.asarray(self.frame, dtype=float)
        Tb: np.ndarray = sla.block_diag(
            np.kron(np.eye(2 * len(self.nodes)), frame), np.eye(self.n_modes)
        )
        return Tb @ x @ Tb.T

    def _modal_speed_term(self, e: np.ndarray, s: int) -> SpeedTerm:
        """The exact body-frame inertia formula of the module docstring (modal bodies)."""
        glob: dict[str, Any] = {
            n: None if getattr(self, n) is None else self._global(getattr(self, n))
            for n in ("M", "K", "D", "G", "C")
        }
        if s == 0:
            D0 = {} if glob["D"] is None else {0: {0: glob["D"]}}
            return SpeedTerm(dofs=self.dofs, M={0: {0: glob["M"]}}, D=D0, K={0: {0: glob["K"]}})
        if glob["G"] is None or glob["C"] is None:
            raise ModelError(
                "a condensed body with modes spins only with its Coriolis and centrifugal "
                "matrices: condense it with `spin_axis`"
            )
        nb = 6 * len(self.nodes)
        R = {
            k: sla.block_diag(np.kron(np.eye(nb // 3), P), np.eye(self.n_modes) * (k == 0))
            for k, P in rotation_series(e, s).items()
        }
        dR = derivative(R, 1.0)
        ddR = derivative(R, 1.0, 2)

        def sandwich(A: dict, X: np.ndarray, B: dict) -> dict[int, np.ndarray]:
            out: dict[int, np.ndarray] = {}
            for ka, Pa in A.items():
                left = Pa @ X
                for kb, Pb in B.items():
                    out[ka + kb] = out.get(ka + kb, 0) + left @ Pb.T
            return clean_series(out)

        M, G, C = glob["M"], glob["G"], glob["C"]
        D: dict[int, dict[int, np.ndarray]] = {
            1: add_series(
                {k: 2 * v for k, v in sandwich(R, M, dR).items()},
                {k: s * v for k, v in sandwich(R, G, R).items()},
            )
        }
        K = {
            0: sandwich(R, glob["K"], R),
            2: add_series(
                sandwich(R, M, ddR),
                {k: s * v for k, v in sandwich(R, G, dR).items()},
                {k: s * s * v for k, v in sandwich(R, C, R).items()},
            ),
        }
        if glob["D"] is not None:
            D[0] = sandwich(R, glob["D"], R)
            K[1] = sandwich(R, glob["D"], dR)
        return SpeedTerm(dofs=self.dofs, M={0: sandwich(R, M, R)}, D=D, K=K)

    def term(self, axis: object, s: int, w1: float) -> Term:
        """:class:`Term` of the body spinning at ``W = s * w1`` about ``axis``."""
        t = self.speed_term(axis, s).at(w1)
        return Term(dofs=t.dofs, M=t.M, D=clean_series(t.D) if t.D else {}, K=clean_series(t.K))

    def speed_term(self, axis: object, s: int) -> SpeedTerm:
        """:meth:`term` as a polynomial in ``w1``: the circulatory stiffness ``Rt D_B Rt'^T``
        and the gyroscopic damping ``W G`` are its linear part."""
        e = unit_axis(axis)
        if self.n_modes or self.C is not None:
            return self._modal_speed_term(e, s)
        M = rotate_body_matrix(self._global(self.M), e, s)
        K = {0: rotate_body_matrix(self._global(self.K), e, s)}
        D: dict[int, dict[int, np.ndarray]] = {}
        if self.D is not None:
            Dg = self._global(self.D)
            D[0] = rotate_body_matrix(Dg, e, s)
            K[1] = circulatory_matrix(Dg, e, s, 1.0)
        if self.G is not None and s != 0:
            G = rotate_body_matrix(self._global(self.G), e, s)
            D[1] = {k: s * v for k, v in G.items()}
        return SpeedTerm(dofs=self.dofs, M={0: M}, D=D, K=K)


#: Arrays of a condensed-body ``.npz`` (those written by :meth:`rheolin.fe.CondensedFE.save`).
_NPZ_KEYS = {
    "M",
    "K",
    "D",
    "G",
    "C",
    "nodes",
    "frame",
    "positions",
    "n_modes",
    "interface",
    "frequencies",
    "rigid_body_modes",
    "spin_axis",
    "recovery",
    "recovery_dofs",
}


def load_condensed(
    path: str | Path | None = None,
    *,
    M: str | Path | None = None,
    K: str | Path | None = None,
    D: str | Path | None = None,
    G: str | Path | None = None,
    nodes: Sequence[int] | None = None,
    frame: np.ndarray | None = None,
) -> CondensedBody:
    """Load a condensed body from one ``.npz`` (keys ``M, K`` and optionally ``D, G, nodes,
    frame``) or from separate matrix files (``.mtx``/``.npy``) given as ``M=..., K=...``.

    Arguments ``nodes`` and ``frame`` override the file's.

    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "body.npz")
    >>> np.savez(p, M=np.eye(6), K=np.eye(6), nodes=np.array([2]))
    >>> load_condensed(p).dofs.tolist()
    [12, 13, 14, 15, 16, 17]
    """
    data: dict[str, object] = {}
    if path is not None:
        p = Path(path)
        if p.suffix != ".npz":
            raise ModelError(f"`path` must be a .npz file, got {str(p)!r}")
        with np.load(p) as z:
            data = {k: z[k] for k in z.files}
        unknown = set(data) - _NPZ_KEYS
        if unknown:
            raise ModelError(
                f"unknown arrays {sorted(unknown)} in {str(p)!r}; allowed: {sorted(_NPZ_KEYS)}"
            )
        if "nodes" not in data and "positions" in data:
            data["nodes"] = np.arange(len(np.asarray(data["positions"])))
    for name, f in (("M", M), ("K", K), ("D", D), ("G", G)):
        if f is not None:
            data[name] = load_matrix(f)
    if nodes is not None:
        data["nodes"] = np.asarray(nodes)
    if frame is not None:
        data["frame"] = np.asarray(frame)
    for name in ("M", "K", "nodes"):
        if name not in data:
            raise ModelError(f"condensed body needs `{name}`")
    return CondensedBody(
        n_modes=int(np.asarray(data.get("n_modes", 0))),
        C=data.get("C"),  # type: ignore[arg-type]
        M=data["M"],  # type: ignore[arg-type]
        K=data["K"],  # type: ignore[arg-type]
        nodes=np.asarray(data["nodes"]).ravel().tolist(),
        D=data.get("D"),  # type: ignore[arg-type]
        G=data.get("G"),  # type: ignore[arg-type]
        frame=data.get("frame"),  # type: ignore[arg-type]
    )


def condensed_body(
    positions: Any, M: Any, K: Any, D: Any, G: Any, frame: Any, path: str | None, body: Any
) -> tuple[np.ndarray, CondensedBody]:
    """The node positions (``n x 3``) and the :class:`CondensedBody` with body-local nodes of
    a condensed body given by exactly one of: its matrices, a ``.npz`` ``path``, or a
    ``body`` (:class:`rheolin.fe.CondensedFE`), whose reference points and file positions are
    the default ``positions`` (``Model.add_condensed_body`` names the arguments).

    >>> pts, cb = condensed_body([[0, 0, 1]], np.eye(6), np.eye(6), None, None, None, None, None)
    >>> pts.tolist(), cb.dofs.tolist()
    ([[0.0, 0.0, 1.0]], [0, 1, 2, 3, 4, 5])
    """
    if body is not None:
        if path is not None or M is not None:
            raise ModelError("give one of `body`, `path` or the matrices `M`, `K`")
        M, K, D, G = body.M, body.K, body.D, body.G
    if positions is None:
        if body is not None:
            positions = body.positions
        elif path is not None:
            with np.load(path) as z:
                if "positions" not in z.files:
                    raise ModelError("`positions`: required (the file has no `positions`)")
                positions = z["positions"]
        else:
            raise ModelError("`positions`: give one 3-vector per node")
    pts = np.asarray(positions, dtype=float).reshape(-1, 3)
    nodes = list(range(len(pts)))  # body-local; the assembly maps them to global nodes
    axes = None if frame is None else np.asarray(frame, dtype=float)
    if body is not None:
        cb = CondensedBody(
            M=M, K=K, nodes=nodes, D=D, G=G, frame=axes, n_modes=body.n_modes, C=body.C
        )
    elif path is not None:
        if M is not None or K is not None:
            raise ModelError("give either `path` or the matrices `M`, `K`, not both")
        cb = load_condensed(path, nodes=nodes, frame=axes)
    else:
        if M is None or K is None:
            raise ModelError("a condensed body needs `M` and `K` (or a `path`)")
        cb = CondensedBody(M=M, K=K, nodes=nodes, D=D, G=G, frame=axes)
    return pts, cb
