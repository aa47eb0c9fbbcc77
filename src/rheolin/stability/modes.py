"""Modes of the time-averaged system ``M_0 q'' + D_0 q' + K_0 q = 0`` and their whirl.

Dense QZ for small models; for large ones shift-invert Arnoldi on the balanced first-order
pencil (the Hill pencil with the single harmonic 0), so no dense ``N x N`` matrix is formed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..floquet.averaged import standard_problem
from ..harmonics.hill import hill_pencil, state_scaling
from ..mechanics.rotation import transverse_basis
from ..system.periodic import PeriodicSystem

__all__ = [
    "AveragedModes",
    "averaged_modes",
    "mac",
    "mode_energy",
    "mode_kind",
    "planetary_kinds",
    "whirl_ratio",
]

#: Above this first-order size the averaged modes are found by shift-invert.
DENSE_MODES_LIMIT = 1200
#: Eigenvalues below this fraction of ``||A||_1 / ||B||_1`` of the first-order pencil are
#: rigid-body modes (exactly zero; a sparse solve resolves their Jordan block only to about the
#: square root of its tolerance), removed from the oscillatory modes.
RIGID_MODE_RTOL = 1e-5
#: ``|whirl ratio|`` above this is called forward or backward whirl.
WHIRL_THRESHOLD = 0.5
#: A mode with at least this share of its kinetic energy in one kind of motion (lateral,
#: torsional, axial) is labelled by it; below, it is ``coupled``.
KIND_SHARE = 0.8
#: The kinds of motion, in the order of :func:`mode_energy`'s columns.
KINDS = ("lateral", "torsional", "axial", "other")
_COMPONENTS = ("ux", "uy", "uz", "phix", "phiy", "phiz")


@dataclass
class AveragedModes:
    """Oscillatory modes (``Im lambda > 0``) of the averaged system, by increasing frequency.

    Attributes
    ----------
    eigenvalues
        ``lambda = -zeta w_n + i w_d`` [1/s].
    shapes
        Displacement shapes ``q`` (columns), unit 2-norm.
    rigid_eigenvalues
        Eigenvalues found at zero (within :data:`RIGID_MODE_RTOL` of the pencil's scale) and
        left out: rigid-body modes (free axial or torsional motion), two per mode.
    """

    eigenvalues: np.ndarray
    shapes: np.ndarray
    rigid_eigenvalues: int = 0

    @property
    def frequency(self) -> np.ndarray:
        """Damped natural frequency ``Im lambda`` [rad/s]."""
        return np.asarray(self.eigenvalues.imag)

    @property
    def damping_ratio(self) -> np.ndarray:
        """``-Re lambda / |lambda|`` (negative: a growing mode)."""
        return np.asarray(-self.eigenvalues.real / np.abs(self.eigenvalues))

    @property
    def log_decrement(self) -> np.ndarray:
        """``-2 pi Re lambda / Im lambda`` (negative: a growing mode)."""
        return np.asarray(-2 * np.pi * self.eigenvalues.real / self.eigenvalues.imag)


def _averaged(system: PeriodicSystem) -> PeriodicSystem:
    M, D, K = (table.get(0) for table in (system.M, system.D, system.K))
    return PeriodicSystem(
        system.omega,
        M=None if M is None else {0: M},
        D=None if D is None else {0: D},
        K=None if K is None else {0: K},
    )


def averaged_modes(
    system: PeriodicSystem, n_modes: int | None = None, *, method: str = "auto"
) -> AveragedModes:
    """The ``n_modes`` lowest oscillatory modes of the time-averaged system.

    Parameters
    ----------
    system
        Periodic system; only ``M_0``, ``D_0``, ``K_0`` are used.
    n_modes
        Number of modes (default: all for the dense method, 12 for the sparse one).
    method
        ``"dense"``, ``"sparse"`` or ``"auto"`` (dense up to a first-order size of
        ``DENSE_MODES_LIMIT``).

    Examples
    --------
    Two uncoupled oscillators, 1 and 2 rad/s, with 1 % damping:

    >>> import numpy as np, rheolin as rl
    >>> s = rl.PeriodicSystem(1.0, M={0: np.eye(2)}, D={0: np.diag([0.02, 0.04])},
    ...                       K={0: np.diag([1.0, 4.0])})
    >>> m = averaged_modes(s)
    >>> np.round(m.frequency, 4), np.round(m.damping_ratio, 4)
    (array([0.9999, 1.9999]), array([0.01, 0.01]))
    """
    link = system.constraint
    if link is not None:  # rigid links: the modes of the constrained system, on every DOF
        system = link.reduce(system)
    avg = _averaged(system)
    n = avg.n
    if method == "auto":
        method = "dense" if 2 * n <= DENSE_MODES_LIMIT else "sparse"
    if method not in ("dense", "sparse"):
        raise ValueError(f"`method` must be 'auto', 'dense' or 'sparse', got {method!r}")
    A, B = hill_pencil(avg, [0])
    sq, _ = state_scaling(avg)
    if method == "dense":
        lam, vec = _dense_modes(A.toarray(), B.toarray(), n)
    else:
        k = 2 * (12 if n_modes is None else int(n_modes)) + 4
        lam, vec = _sparse_low_modes(A, B, min(k, 2 * n - 2))
    ok = np.isfinite(lam)
    lam, vec = lam[ok], vec[:, ok]
    scale = max(float(np.abs(lam).max()) if lam.size else 1.0, 1.0)
    # rigid-body modes (a free axial or torsional motion): eigenvalue 0, a Jordan block that
    # shift-invert resolves only to about sqrt(tolerance) of the pencil's scale
    zero = RIGID_MODE_RTOL * max(float(spla.norm(A, 1) / max(spla.norm(B, 1), 1e-300)), 1e-300)
    rigid = np.abs(lam) <= zero
    osc = (lam.imag > 1e-9 * scale) & ~rigid
    lam, vec = lam[osc], vec[:, osc]
    order = np.argsort(lam.imag, kind="stable")
    if n_modes is not None:
        order = order[: int(n_modes)]
    lam, q = lam[order], vec[:n, order] / sq[:, None]
    if link is not None:
        q = link.expand(q.T).T
    with np.errstate(under="ignore"):
        q = q / np.maximum(np.linalg.norm(q, axis=0), np.finfo(float).tiny)
    return AveragedModes(lam, q, int(rigid.sum()))


def _dense_modes(A: np.ndarray, B: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues and right vectors of ``lambda B y = A y`` (first order, ``2 n``,
    ``B = diag(I, M)`` balanced): the standard problem ``B^-1 A`` (one solve with the mass
    block, then an eigen-solve several times faster than QZ) when ``B`` is well conditioned
    (:func:`~rheolin.floquet.averaged.standard_problem`), else QZ.

    >>> A = np.array([[0.0, 1.0], [-4.0, -0.4]]); B = np.diag([1.0, 2.0])
    >>> lam, _ = _dense_modes(A, B, 1)
    >>> np.allclose(np.sort_complex(lam), np.sort_complex(np.roots([2.0, 0.4, 4.0])))
    True
    """
    Ms = B[n:, n:]
    with np.errstate(under="ignore", invalid="ignore", divide="ignore"):
        if n and standard_problem(Ms):
            C = np.array(A, dtype=np.result_type(A, Ms))
            C[n:] = np.linalg.solve(Ms, A[n:])
            if np.iscomplexobj(C) and not np.any(C.imag):
                C = C.real
            lam, vec = sla.eig(C, check_finite=False, overwrite_a=True)
            if not _repeated(lam):
                return lam, vec
        # QZ, also for repeated eigenvalues: the basis it returns in their eigenspaces (which
        # sets a degenerate pair's whirl) stays the one the diagrams have always shown
        lam, vec = sla.eig(A, B, check_finite=False)
    return lam, vec


def _repeated(lam: np.ndarray) -> bool:
    """Whether two finite eigenvalues agree to 1e-8 of their size (a degenerate pair).

    >>> _repeated(np.array([1j, 1j * (1 + 1e-12), 2j])), _repeated(np.array([1j, 2j]))
    (True, False)
    """
    z = lam[np.isfinite(lam)]
    z = z[np.lexsort((z.real, z.imag))]  # by frequency, then damping (real roots: by value)
    for step in range(1, min(z.size, 5)):  # neighbours (conjugates and copies interleave)
        scale = np.maximum(np.abs(z[step:]), np.abs(z[:-step]))
        if np.any(np.abs(z[step:] - z[:-step]) <= 1e-8 * np.maximum(scale, 1e-300)):
            return True
    return False


def _sparse_low_modes(A: sp.csc_array, B: sp.csc_array, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues nearest 0 of ``lambda B y = A y`` (one sparse LU), from a fixed starting
    vector so that repeated runs return the same modes."""
    size = A.shape[0]
    sigma = 0.0
    try:
        lu = spla.splu(sp.csc_array(A), permc_spec="MMD_ATA")
    except RuntimeError:  # rigid-body mode: shift off the origin
        sigma = -1e-3 * (spla.norm(A, 1) / max(spla.norm(B, 1), 1e-300))
        lu = spla.splu(sp.csc_array(A - sigma * B), permc_spec="MMD_ATA")
    op = spla.LinearOperator((size, size), matvec=lambda x: lu.solve(B @ x), dtype=complex)
    v0 = np.random.default_rng(0).standard_normal(size)  # fixed: the same modes every run
    nu, vec = spla.eigs(op, k=k, which="LM", tol=1e-12, v0=v0.astype(complex))
    return sigma + 1.0 / nu, vec


def whirl_ratio(
    shapes: np.ndarray,
    dof_labels: Sequence[tuple[str, int, str]],
    axes: Mapping[str, np.ndarray],
    spins: Mapping[str, int],
) -> np.ndarray:
    """Whirl of each mode shape: ``+1`` pure forward, ``-1`` pure backward, ``0`` none.

    For every node of a spinning body, the transverse translations and tilts (perpendicular
    to the spin axis ``e``, basis ``(a, b)`` with ``a x b = e``) of the complex shape ``X``
    (motion ``Re(X e^{i w t})``, ``w > 0``) split into circles turning with the body
    (``|X_a + i X_b|`` when the body spins positively about ``e``) and against it
    (``|X_a - i X_b|``). The ratio is ``(F - B) / (F + B)`` with ``F``, ``B`` the summed squared
    radii; DOFs of non-rotating bodies do not count.

    >>> X = np.array([[1.0], [-1j], [0], [0], [0], [0]])  # x = cos wt, y = sin wt
    >>> labels = [("s", 0, c) for c in ("ux", "uy", "uz", "phix", "phiy", "phiz")]
    >>> whirl_ratio(X, labels, {"s": np.array([0, 0, 1.0])}, {"s": 1})
    array([1.])
    """
    index = {lab: i for i, lab in enumerate(dof_labels)}
    fwd = np.zeros(shapes.shape[1])
    bwd = np.zeros(shapes.shape[1])
    nodes = sorted({(b, i) for b, i, _ in dof_labels})
    for body, node in nodes:
        s = spins.get(body, 0)
        if s == 0:
            continue
        a, b = transverse_basis(axes[body])
        for kind in (("ux", "uy", "uz"), ("phix", "phiy", "phiz")):
            found = [index.get((body, node, c)) for c in kind]
            if any(r is None for r in found):
                continue
            X = shapes[[int(r) for r in found if r is not None], :]
            xa, xb = a @ X, b @ X
            with np.errstate(under="ignore"):
                p = np.abs(xa + 1j * xb) ** 2
                m = np.abs(xa - 1j * xb) ** 2
            if s < 0:
                p, m = m, p
            fwd += p
            bwd += m
    total = fwd + bwd
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(
            total > 1e-12 * max(float(total.max(initial=0.0)), 1e-300),
            (fwd - bwd) / np.where(total > 0, total, 1.0),
            0.0,
        )
    return np.asarray(ratio)


def mode_energy(
    shapes: np.ndarray,
    dof_labels: Sequence[tuple[str, int, str]],
    axes: Mapping[str, np.ndarray],
    M0: Any,
) -> np.ndarray:
    """Share of each mode's kinetic energy in lateral, torsional, axial and other motion.

    Per node, with its body's axis ``e``: the translation along ``e`` is axial, the rotation
    about ``e`` torsional, the rest (transverse translations and tilts) lateral, each weighted
    by the node's 3 x 3 translational and rotational blocks of ``M0`` (``x^H M x`` of that part);
    DOFs without a node (modal DOFs of condensed bodies) are ``other``. Returns ``(n_modes, 4)``
    in the order of :data:`KINDS`, rows summing to 1.

    >>> labels = [("s", 0, c) for c in ("ux", "uy", "uz", "phix", "phiy", "phiz")]
    >>> X = np.array([[0, 0, 0, 0, 0, 1.0], [1.0, 0, 0, 0, 0, 0]]).T  # a twist, a bending
    >>> mode_energy(X, labels, {"s": np.array([0, 0, 1.0])}, np.eye(6)).round(3).tolist()
    [[0.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]]
    """
    M = sp.csr_array(M0) if sp.issparse(M0) else np.asarray(M0)

    def block(r: np.ndarray) -> np.ndarray:
        if sp.issparse(M):
            return np.asarray(M[r][:, r].toarray())
        return np.asarray(M[np.ix_(r, r)])

    index = {lab: i for i, lab in enumerate(dof_labels)}
    energy = np.zeros((shapes.shape[1], len(KINDS)))
    seen = np.zeros(len(dof_labels), dtype=bool)
    for body, node in sorted({(b, i) for b, i, c in dof_labels if c in _COMPONENTS}):
        e = np.asarray(axes[body], dtype=float)
        P = np.eye(3) - np.outer(e, e)
        for comps, along in ((_COMPONENTS[:3], 2), (_COMPONENTS[3:], 1)):
            rows = [index.get((body, node, c)) for c in comps]
            if any(r is None for r in rows):
                continue
            r = np.array(rows, dtype=int)
            seen[r] = True
            X, W = shapes[r, :], block(r)
            for part, col in ((np.outer(e, e) @ X, along), (P @ X, 0)):
                energy[:, col] += np.real(np.einsum("im,ij,jm->m", part.conj(), W, part))
    rest = np.flatnonzero(~seen)
    if rest.size:
        X, W = shapes[rest, :], block(rest)
        energy[:, 3] += np.real(np.einsum("im,ij,jm->m", X.conj(), W, X))
    energy = np.maximum(energy, 0.0)
    total = energy.sum(axis=1, keepdims=True)
    return np.asarray(energy / np.where(total > 0, total, 1.0))


def mode_kind(energy: np.ndarray, whirl: np.ndarray) -> np.ndarray:
    """Labels from :func:`mode_energy` and :func:`whirl_ratio`: ``"lateral forward"``,
    ``"lateral backward"``, ``"lateral"`` (no whirl: a non-spinning body, or mixed),
    ``"torsional"``, ``"axial"``, or ``"coupled (lateral+torsional)"`` etc. (no kind holds
    :data:`KIND_SHARE` of the energy; the two largest are named).

    >>> mode_kind(np.array([[0.95, 0.05, 0, 0], [0.5, 0.45, 0.05, 0]]), np.array([-1.0, 0.0]))
    array(['lateral backward', 'coupled (lateral+torsional)'], dtype=object)
    """
    out = np.empty(energy.shape[0], dtype=object)
    for m, (row, r) in enumerate(zip(energy, whirl, strict=True)):
        k = int(np.argmax(row))
        if row[k] >= KIND_SHARE:
            label = KINDS[k]
            if label == "lateral" and np.isfinite(r) and abs(r) >= WHIRL_THRESHOLD:
                label += " forward" if r > 0 else " backward"
            out[m] = label
        else:
            a, b = np.argsort(-row, kind="stable")[:2]
            out[m] = f"coupled ({KINDS[int(a)]}+{KINDS[int(b)]})"
    return out


def planetary_kinds(kinds: np.ndarray, shapes: np.ndarray, model: Any, a: Any) -> np.ndarray:
    """``kinds`` with the modes that live in a planetary set labelled by Lin & Parker's types
    (:mod:`rheolin.mechanics.planetary_modes`): ``"rotational (stage1)"``, ``"translational
    (stage1)"``, ``"planet (stage1)"``, ``"coupled (stage1)"``; the others unchanged."""
    sets = getattr(model, "planetary", {})
    if not sets:
        return kinds
    from ..mechanics.planetary_modes import SetDofs, planetary_mode_kinds

    out = np.asarray(kinds, dtype=object).copy()
    M0 = a.system.M[0]
    m = np.asarray(M0.diagonal() if sp.issparse(M0) else np.diag(M0), dtype=float)
    for name, s in sets.items():
        members = [a.dofs(*ref) for ref in (s.sun, s.ring, s.carrier)]
        dofs = SetDofs(
            np.concatenate([d[:2] for d in members]),
            np.array([d[5] for d in members]),
            np.concatenate([a.dofs(p, 0) for p in s.planets]),
        )
        labels = planetary_mode_kinds(shapes, m, dofs)
        for j, lab in enumerate(labels):
            if lab:
                out[j] = f"{lab} ({name})"
    return out


def mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Modal assurance criterion ``|a_i^H b_j|^2 / (|a_i|^2 |b_j|^2)`` of the columns.

    >>> mac(np.eye(2), np.array([[1.0, 1.0], [0.0, 1.0]])).round(2).tolist()
    [[1.0, 0.5], [0.0, 0.5]]
    """
    num = np.abs(a.conj().T @ b) ** 2
    na = np.sum(np.abs(a) ** 2, axis=0)
    nb = np.sum(np.abs(b) ** 2, axis=0)
    return np.asarray(num / np.maximum(np.outer(na, nb), 1e-300))
