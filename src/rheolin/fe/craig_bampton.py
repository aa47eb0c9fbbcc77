"""Craig-Bampton condensation of a large FE body: :func:`condense`.

The FE DOFs ``u`` are first tied to the interface reference nodes (:mod:`rheolin.fe.coupling`,
``u = T [q; v]``); then, with ``K_ii``, ``M_ii`` the matrices of the inner DOFs ``v``,

    v = Psi q + Phi eta,   Psi = -K_ii^-1 K_iq (static constraint modes),
    K_ii Phi = M_ii Phi Lambda (fixed-interface modes, the lowest ``modes``, mass-normalized),

and the body keeps ``6 x interfaces + modes`` DOFs: the reference nodes' translations and
rotations (3-vectors in global axes, like every rheolin node) and the modal amplitudes. One
factorization of ``K_ii`` (the sparse backend of :mod:`rheolin.linalg.direct`) gives both
the constraint modes and the shift-invert Lanczos (``eigsh``) of the fixed-interface modes.
Mass, stiffness and damping are reduced as ``X_r = Y^T X Y`` with ``Y = T [[I, 0], [Psi, Phi]]``
and symmetrized.

Free bodies: with the interface fixed the inner DOFs cannot move rigidly (a coupling holds all
six DOFs of its reference node), so ``K_ii`` is nonsingular and the rigid-body motions of the
whole body lie in the span of the constraint modes, exactly. :func:`condense` detects them
(``K_r R = 0`` for the rigid motions ``R`` of the reference nodes), reports their number in
``rigid_body_modes`` and removes the round-off from ``K_r`` by the mass-orthogonal projection
``P^T K_r P``, so the free body has six exact zero frequencies; it must then be supported by
bearings or joints in the model. A body clamped by ``fixed`` DOFs has none.

Spinning bodies (``spin_axis``): the reduced Coriolis matrix ``G = Y^T (M E - E M) Y``
(per unit speed, ``E`` the cross product with the axis on every FE translation) and the
centrifugal matrix ``C = Y^T M E^2 Y`` (per unit speed squared) are kept; the model turns the
body-frame equations into the inertial frame (:mod:`rheolin.mechanics.condensed`). For a free
body, ``C`` also holds the centrifugal stress stiffening of its rigid motions, so that a
condensed rigid body spins exactly as Euler's equations say (:func:`_rigid_stress_stiffening`);
that of its elastic modes is not modelled.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import ModelError
from ..io.atomic import atomic_write
from ..linalg.direct import analyze, resolve_backend
from .coupling import Coupling, coupling_transform, rigid_map, skew
from .matrices import FEModel

__all__ = ["CondensedFE", "condense"]

log = logging.getLogger(__name__)


@dataclass
class CondensedFE:
    """A condensed FE body: matrices over ``6 x len(interface)`` interface DOFs (node-major,
    ``ux uy uz phix phiy phiz`` in the FE model's axes) followed by ``n_modes`` modal DOFs.

    Attributes
    ----------
    M, K, D, G, C
        Reduced mass, stiffness, damping (or None), Coriolis matrix per unit spin speed and
        centrifugal matrix per unit spin speed squared (None for a body that does not spin).
    interface, positions
        Interface names and reference positions ``(n, 3)``.
    frequencies
        Fixed-interface natural frequencies of the kept modes [Hz].
    rigid_body_modes
        Rigid-body modes of the condensed body (6 for a free body, 0 when clamped).
    recovery
        ``u_out = recovery @ x``: FE DOFs ``recovery_dofs`` from the body's DOFs (optional).
    """

    M: np.ndarray
    K: np.ndarray
    interface: list[str]
    positions: np.ndarray
    frequencies: np.ndarray
    rigid_body_modes: int
    D: np.ndarray | None = None
    G: np.ndarray | None = None
    C: np.ndarray | None = None
    spin_axis: np.ndarray | None = None
    recovery: np.ndarray | None = None
    recovery_dofs: np.ndarray | None = None
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def n_modes(self) -> int:
        """Modal DOFs kept."""
        return int(self.frequencies.size)

    def save(self, path: str | Path) -> None:
        """Write an ``.npz`` that :func:`rheolin.mechanics.condensed.load_condensed` and the
        model file (``[[condensed_bodies]] path``) read (written atomically)."""
        arrays: dict[str, Any] = {
            "M": self.M,
            "K": self.K,
            "positions": self.positions,
            "n_modes": np.array(self.n_modes),
            "interface": np.array(self.interface),
            "frequencies": self.frequencies,
            "rigid_body_modes": np.array(self.rigid_body_modes),
        }
        for name in ("D", "G", "C", "spin_axis", "recovery", "recovery_dofs"):
            if getattr(self, name) is not None:
                arrays[name] = getattr(self, name)
        with atomic_write(Path(path)) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, **arrays)


def _as_fe(K: Any, M: Any, D: Any, coordinates: Any) -> FEModel:
    if isinstance(K, FEModel):
        if M is not None or D is not None:
            raise ModelError("give the matrices inside the FEModel, not as `M`/`D` as well")
        return K
    if M is None or coordinates is None:
        raise ModelError("`condense(K, M, ...)` needs `M` and `coordinates` (or an FEModel)")
    return FEModel.solid(K, M, np.asarray(coordinates), D=D)


def _spin_operator(fe: FEModel, axis: np.ndarray) -> sp.csr_array:
    """``E``: the cross product with ``axis`` on every node's translations."""
    Ex = np.cross(axis, np.eye(3)).T  # column i is axis x e_i: Ex @ v == cross(axis, v)
    rows, cols, vals = [], [], []
    node_dofs: dict[int, dict[int, int]] = {}
    for d, (node, comp) in enumerate(zip(fe.dof_node, fe.dof_component, strict=True)):
        if comp < 3:
            node_dofs.setdefault(int(node), {})[int(comp)] = d
    for dofs in node_dofs.values():
        for a, da in dofs.items():
            for b, db in dofs.items():
                if Ex[a, b]:
                    rows.append(da)
                    cols.append(db)
                    vals.append(Ex[a, b])
    return sp.csr_array((vals, (rows, cols)), shape=(fe.n_dof, fe.n_dof))


def condense(
    K: Any,
    M: Any = None,
    interface: Sequence[Coupling] = (),
    modes: int = 20,
    D: Any = None,
    *,
    coordinates: Any = None,
    fixed: Sequence[int] | np.ndarray | None = None,
    cutoff_hz: float | None = None,
    spin_axis: Sequence[float] | None = None,
    recover: Sequence[int] | np.ndarray | None = None,
    sparse_backend: str = "auto",
) -> CondensedFE:
    """Craig-Bampton reduction of an FE body to its interface nodes and fixed-interface modes.

    Parameters
    ----------
    K, M
        Stiffness and mass of the FE body (sparse, symmetric), or an
        :class:`~rheolin.fe.matrices.FEModel` as ``K`` (then ``M=None``).
    interface
        :class:`~rheolin.fe.coupling.Coupling` per rheolin node (bearing seats, flanges).
    modes
        Fixed-interface modes to keep (the lowest); at least those below ``cutoff_hz``.
    D
        Viscous damping of the FE body (reduced alike), or None.
    coordinates
        Node positions ``(n_nodes, 3)`` when ``K`` is a matrix of translational DOFs
        (``3 i + c``).
    fixed
        FE DOFs clamped to ground (a housing's feet); they are removed.
    cutoff_hz
        Keep every fixed-interface mode below this frequency (more than ``modes`` if need be).
        Rule: 4 times the highest frequency of interest kept the modes below it within
        1e-3 on a free bar with averaged end faces (2 times: 8e-3); a cantilever needed 6
        times (4 times: 1.5e-3). Check the convergence on your model (tests/fe).
    spin_axis
        Unit spin axis in the FE axes for a body that rotates; None for a fixed one.
    recover
        FE DOFs whose response can be recovered (``CondensedFE.recovery``).
    sparse_backend
        Factorization of ``K_ii`` (:mod:`rheolin.linalg.direct`).

    Examples
    --------
    A free steel cube (one element), its top face averaged to a node at its centre:

    >>> from rheolin.fe.solid import solid_model, tensor_block
    >>> fe = solid_model(*tensor_block((0.1, 0.1, 0.1), (2, 2, 2)))
    >>> top = fe.nodes_where(lambda x: x[:, 2] > 0.099)
    >>> body = condense(fe, None, [Coupling("top", top, [0.05, 0.05, 0.1])], modes=6)
    >>> body.M.shape, body.rigid_body_modes
    ((12, 12), 6)
    """
    fe = _as_fe(K, M, D, coordinates)
    if not interface:
        raise ModelError("`interface`: give at least one Coupling (the body's rheolin nodes)")
    names = [c.name for c in interface]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ModelError(
            f"`interface`: the names {twice} are used more than once; each interface is one "
            "rheolin node and needs its own name"
        )
    if isinstance(modes, bool) or int(modes) < 0:
        raise ModelError(f"`modes` must be a nonnegative integer, got {modes!r}")
    if cutoff_hz is not None and not (np.isfinite(cutoff_hz) and cutoff_hz > 0):
        raise ModelError(f"`cutoff_hz` must be a finite frequency > 0 [Hz], got {cutoff_hz!r}")
    for what, X in (("M", fe.M), ("K", fe.K)):
        low = float(np.min(X.diagonal(), initial=0.0))
        if low < 0:
            i = int(np.argmin(X.diagonal()))
            raise ModelError(
                f"`{what}`: the {'mass' if what == 'M' else 'stiffness'} matrix has a negative "
                f"diagonal entry {low:.4g} at FE DOF {i}; it must be positive semidefinite"
            )
    T, free = coupling_transform(fe, interface)
    nb = 6 * len(interface)
    if fixed is not None:
        fixed = np.unique(np.asarray(fixed, dtype=np.int64))
        if np.isin(fixed, np.setdiff1d(np.arange(fe.n_dof), free)).any():
            raise ModelError("`fixed`: a clamped DOF belongs to an interface node set")
        keep = np.concatenate([np.arange(nb), nb + np.flatnonzero(~np.isin(free, fixed))])
        T = sp.csr_array(T[:, keep])
    Tc = sp.csc_array(T)
    Kt = sp.csr_array(Tc.T @ fe.K @ Tc)
    Mt = sp.csr_array(Tc.T @ fe.M @ Tc)
    n_i = Kt.shape[0] - nb
    if n_i <= 0:
        raise ModelError("`interface`: nothing is left inside the body to condense")
    Kii = sp.csc_array(Kt[nb:, nb:])
    Kii.sort_indices()
    Mii = sp.csr_array(Mt[nb:, nb:])
    name = resolve_backend(sparse_backend, (Kii.indptr, Kii.indices, Kii.shape[0]))
    factor = analyze(name, Kii.indptr, Kii.indices, False, sample=Kii.data).factor(Kii.data)
    # the factor serves every constraint mode and every Lanczos step: check it on a probe and
    # redo it with SuperLU when it is not accurate
    probe = np.cos(np.arange(n_i) * 0.37)
    err = np.linalg.norm(Kii @ np.asarray(factor.solve(probe)).real - probe)
    if name != "superlu" and not err <= 1e-8 * np.linalg.norm(probe):
        log.warning("condense: the %s factor failed its probe (%.2g); using SuperLU", name, err)
        factor = analyze("superlu", Kii.indptr, Kii.indices, False).factor(Kii.data)
    Kib = Kt[nb:, :nb].toarray()
    Psi = -np.asarray(factor.solve(Kib)).real
    scale = np.linalg.norm(Kib) + 1e-300
    if not np.linalg.norm(Kii @ Psi + Kib) <= 1e-8 * scale:
        raise ModelError(
            "`interface`: the inner DOFs can move freely with the interface fixed (a part of "
            "the mesh is not connected to any interface, or the model is a mechanism)"
        )
    try:
        lam, Phi = _fixed_interface_modes(Kii, Mii, factor, int(modes), cutoff_hz)
    except (np.linalg.LinAlgError, spla.ArpackError, spla.ArpackNoConvergence) as exc:
        raise ModelError(
            "`M`: the fixed-interface eigenproblem failed: the mass matrix is not positive "
            f"definite on the body's inner DOFs, or the stiffness is singular there ({exc})"
        ) from None
    Y = sp.csr_array(Tc @ _basis(nb, Psi, Phi))
    red = {name: _reduce(mat, Y) for name, mat in (("K", fe.K), ("M", fe.M))}
    Dr = None if fe.D is None else _reduce(fe.D, Y)
    positions = np.array([np.asarray(c.reference, float) for c in interface])
    Kr, rigid = _rigid_body_cleanup(red["K"], red["M"], positions, Phi.shape[1])
    G = C = axis = None
    if spin_axis is not None:
        axis = np.asarray(spin_axis, dtype=float)
        axis = axis / np.linalg.norm(axis)
        E = _spin_operator(fe, axis)
        ME = sp.csr_array(fe.M @ E)
        Yd = Y.toarray()
        MEY = ME @ Yd
        G = Yd.T @ MEY - (Yd.T @ MEY).T  # Y^T (M E - E^T M) Y, E^T = -E
        C = -(E @ Yd).T @ (fe.M @ (E @ Yd))  # Y^T M E^2 Y = -(E Y)^T M (E Y)
        C = 0.5 * (C + C.T)
        if rigid:
            C = C + _rigid_stress_stiffening(red["M"], C, positions, axis)
    rec = rec_dofs = None
    if recover is not None:
        rec_dofs = np.asarray(recover, dtype=np.int64).ravel()
        rec = Y[rec_dofs].toarray()
    return CondensedFE(
        M=red["M"],
        K=Kr,
        D=Dr,
        G=G,
        C=C,
        spin_axis=axis,
        interface=[c.name for c in interface],
        positions=positions,
        frequencies=np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi),
        rigid_body_modes=rigid,
        recovery=rec,
        recovery_dofs=rec_dofs,
        info={"fe_dofs": fe.n_dof, "inner_dofs": n_i, "factor_bytes": factor.nbytes},
    )


def _basis(nb: int, Psi: np.ndarray, Phi: np.ndarray) -> sp.csr_array:
    """``[[I, 0], [Psi, Phi]]`` over (interface, inner) rows and (interface, modal) columns."""
    top = sp.hstack([sp.eye_array(nb), sp.csr_array((nb, Phi.shape[1]))])
    return sp.csr_array(sp.vstack([top, sp.csr_array(np.hstack([Psi, Phi]))]))


def _reduce(X: Any, Y: sp.csr_array) -> np.ndarray:
    Yd = Y.toarray()
    out = Yd.T @ (X @ Yd)
    return np.asarray(0.5 * (out + out.T))


def _fixed_interface_modes(
    Kii: sp.csc_array, Mii: sp.csr_array, factor: Any, modes: int, cutoff_hz: float | None
) -> tuple[np.ndarray, np.ndarray]:
    n = Kii.shape[0]
    if modes == 0 and cutoff_hz is None:
        return np.zeros(0), np.zeros((n, 0))
    op = spla.LinearOperator((n, n), matvec=lambda x: np.asarray(factor.solve(x)).real)
    k = max(modes, 1)
    while True:
        k = min(k, n - 1)
        if n <= 200:
            lam, Phi = sla.eigh(Kii.toarray(), Mii.toarray(), subset_by_index=[0, k - 1])
        else:
            # a fixed start (reproducible) and a few more than needed: Lanczos can miss one of
            # a close pair near the end of what it is asked for, never among the lowest kept
            extra = min(n - 1, k + max(4, k // 4))
            v0 = np.cos(np.arange(n) * 0.618) + 1.0
            lam, Phi = spla.eigsh(
                Kii, k=extra, M=Mii, sigma=0.0, which="LM", OPinv=op, tol=1e-12, v0=v0
            )
        order = np.argsort(lam)[:k]
        lam, Phi = lam[order], Phi[:, order]
        top = np.sqrt(max(lam[-1], 0.0)) / (2 * np.pi)
        if cutoff_hz is None or top >= cutoff_hz or k >= n - 1:
            break
        k *= 2
    if cutoff_hz is not None:
        below = int(np.searchsorted(np.sqrt(np.maximum(lam, 0)) / (2 * np.pi), cutoff_hz))
        keep = max(modes, below + 1)
        lam, Phi = lam[:keep], Phi[:, :keep]
    Phi = Phi / np.sqrt(np.einsum("ij,ij->j", Phi, Mii @ Phi))
    return lam, Phi


def _rigid_motions(positions: np.ndarray, n: int, about: np.ndarray) -> np.ndarray:
    """``R`` (``n x 6``): the reduced coordinates of a rigid motion of the body (translation,
    rotation about ``about``): each interface node moves rigidly, the modal amplitudes stay 0."""
    R = np.zeros((n, 6))
    for j, x in enumerate(positions):
        R[6 * j : 6 * j + 3] = rigid_map(x[None, :], about)
        R[6 * j + 3 : 6 * j + 6, 3:] = np.eye(3)
    return R


def _rigid_stress_stiffening(
    M: np.ndarray, C: np.ndarray, positions: np.ndarray, axis: np.ndarray
) -> np.ndarray:
    """Centrifugal stress stiffening of a free spinning body, on its rigid motions only
    (per unit speed squared; docs/large-models.md).

    The spin softening ``W^2 C`` alone softens a rigid rotation about the axis by
    ``W^2 I_p`` and a tilt by ``W^2 x`` the second moment along the axis; the centrifugal
    prestress turning with the body cancels that. Rigid-body mechanics in the spinning frame
    (Euler's equations linearized about a steady spin about a principal axis ``e`` through the
    mass centre) gives the stiffness per unit ``W^2``: ``-m P`` on translations
    (``P = I - e e^T``) and ``Z J Z + I_p P`` on rotations about the mass centre (``Z = [e]x``,
    ``J`` the inertia tensor there, ``I_p = e^T J e``): no stiffness for the rotation about the
    axis, ``I_p - I_d`` for a tilt. The correction ``S = M R A^-1 (K_rigid - R^T C R) A^-1 R^T M``
    (``A = R^T M R``) makes ``R^T (C + S) R = K_rigid`` exactly and leaves every motion
    mass-orthogonal to the rigid ones alone: the stress stiffening of the elastic modes is not
    modelled (it matters for thin disks or blades spinning near their first frequencies).
    """
    n = M.shape[0]
    R0 = _rigid_motions(positions, n, np.zeros(3))
    A0 = R0.T @ M @ R0
    m = float(np.trace(A0[:3, :3]) / 3)
    cx = -A0[:3, 3:] / m  # t^T A_tr theta = -m t . (c x theta)
    centre = np.array([cx[2, 1], cx[0, 2], cx[1, 0]])
    R = _rigid_motions(positions, n, centre)
    A = R.T @ M @ R
    J = A[3:, 3:]
    Z = skew(axis)
    P = np.eye(3) - np.outer(axis, axis)
    want = np.zeros((6, 6))
    want[:3, :3] = -m * P
    want[3:, 3:] = Z @ J @ Z + float(axis @ J @ axis) * P
    delta = want - R.T @ C @ R
    MR = M @ R
    X = np.linalg.solve(A, MR.T)  # A^-1 R^T M
    S = X.T @ delta @ X
    return 0.5 * (S + S.T)


def _rigid_body_cleanup(
    Kr: np.ndarray, Mr: np.ndarray, positions: np.ndarray, n_modes: int
) -> tuple[np.ndarray, int]:
    """Detect the six rigid-body modes of a free body and remove the round-off from ``K``."""
    R = _rigid_motions(positions, Kr.shape[0], positions.mean(axis=0))
    if np.linalg.norm(Kr @ R) > 1e-8 * np.linalg.norm(Kr) * np.linalg.norm(R):
        return Kr, 0  # restrained (clamped DOFs): no rigid-body motion
    P = np.eye(Kr.shape[0]) - R @ np.linalg.solve(R.T @ Mr @ R, R.T @ Mr)
    K = P.T @ Kr @ P
    return 0.5 * (K + K.T), 6
