"""The solver test catalogue: systems with an independent reference, run by every method.

Each :class:`Case` carries a system factory, the harmonic set, a reference for the harmonic
coefficients that does not use rheolin's operator (a closed form, ``numpy.linalg.solve`` of a
per-frequency system, or a dense harmonic-balance matrix assembled here from the formula of
docs/conventions.md), and the outcome expected from each method. ``test_solvers.py`` runs every case
against every method, the way SciPy tests its iterative solvers on one shared case list.

Conventions (docs/conventions.md): ``X(t) = sum_k X_k exp(i k w1 t)``, so ``F cos(w t)`` has
``f_{+1} = f_{-1} = F / 2``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

import rheolin as rl

METHODS = ("lti", "perturbation", "gmres", "direct")


@dataclass(frozen=True)
class Case:
    """One catalogue entry.

    Attributes
    ----------
    name
        Test id.
    system
        Factory of the :class:`rheolin.PeriodicSystem`.
    harmonics
        Harmonic set for :func:`rheolin.solve`.
    reference
        ``reference(harmonic_indices) -> q`` of shape ``(|H|, n)``, computed independently.
    converge
        Methods that must return ``success=True`` and match the reference.
    fail
        Methods that must return ``success=False``, mapped to the allowed ``status`` codes.
    ref_tol
        Relative agreement required with the reference (2-norm over all coefficients).
    time_invariant
        True when ``M, D, K`` have no harmonics (``lti`` applies); else ``lti`` must refuse.
    """

    name: str
    system: Callable[[], rl.PeriodicSystem]
    harmonics: rl.HarmonicSet
    reference: Callable[[np.ndarray], np.ndarray]
    converge: frozenset[str]
    fail: dict[str, frozenset[int]] = field(default_factory=dict)
    ref_tol: float = 1e-8
    time_invariant: bool = False


# --------------------------------------------------------------------------- Jeffcott rotor
@dataclass(frozen=True)
class Jeffcott:
    """Asymmetric Jeffcott rotor (docs/solvers.md, reference cases): mass ``m``, rotating-frame
    stiffnesses ``k_x``, ``k_y``, stationary damping ``c``, unbalance ``e`` at angle ``beta``,
    speed ``W``, optional gravity ``g`` along ``-y``.

    The system is built in the inertial frame with ``w1 = W``:
    ``K(t) = k_m I + k_d [[cos 2Wt, sin 2Wt], [sin 2Wt, -cos 2Wt]]``.
    """

    W: float
    m: float = 1.0
    kx: float = 1.2
    ky: float = 0.8
    c: float = 0.1
    e: float = 0.01
    beta: float = 0.3
    g: float = 0.0

    @property
    def km(self) -> float:
        return 0.5 * (self.kx + self.ky)

    @property
    def kd(self) -> float:
        return 0.5 * (self.kx - self.ky)

    def coefficients(self) -> tuple[dict, dict, dict, dict]:
        """Fourier coefficients written out from the time functions (both signs of k)."""
        I2 = np.eye(2)
        # cos 2Wt = (e^{2iWt} + e^{-2iWt}) / 2,  sin 2Wt = (e^{2iWt} - e^{-2iWt}) / (2i)
        C, S = np.array([[1.0, 0.0], [0.0, -1.0]]), np.array([[0.0, 1.0], [1.0, 0.0]])
        K2 = self.kd * (C / 2 + S / 2j)
        M = {0: self.m * I2}
        D = {0: self.c * I2}
        K = {0: self.km * I2, 2: K2, -2: np.conj(K2)}
        f: dict[int, np.ndarray] = {}
        if self.e:
            # m e W^2 (cos(Wt + b), sin(Wt + b)): f_{+1} = m e W^2 e^{ib} (1, -i) / 2
            F = self.m * self.e * self.W**2 * np.exp(1j * self.beta)
            f[1] = F * np.array([1.0, -1j]) / 2
            f[-1] = np.conj(f[1])
        if self.g:
            f[0] = np.array([0.0, -self.m * self.g])
        return M, D, K, f

    def system(self, sparse: bool = False) -> rl.PeriodicSystem:
        M, D, K, f = self.coefficients()
        conv = (lambda x: sp.csr_array(x)) if sparse else (lambda x: x)
        pos = lambda d: {k: conv(v) for k, v in d.items() if k >= 0}  # noqa: E731
        return rl.PeriodicSystem(self.W, M=pos(M), D=pos(D), K=pos(K), f=f)

    @property
    def unstable(self) -> bool:
        """Closed-form instability criterion (docs/solvers.md, reference cases)."""
        mW2 = self.m * self.W**2
        return (self.kx - mW2) * (self.ky - mW2) + (self.c * self.W) ** 2 < 0

    def unbalance_response(self, H: np.ndarray) -> np.ndarray:
        """Exact response to unbalance alone: ``x + i y = P e^{iWt}``, only ``n = ±1``.

        ``[[k_x - m W^2, -c W], [c W, k_y - m W^2]] [Re P, Im P] = m e W^2 [cos b, sin b]``;
        ``x = Re(P e^{iWt})``, ``y = Re(-i P e^{iWt})`` give ``q_1 = (P, -iP) / 2``.
        """
        mW2 = self.m * self.W**2
        A = np.array([[self.kx - mW2, -self.c * self.W], [self.c * self.W, self.ky - mW2]])
        rhs = self.m * self.e * self.W**2 * np.array([np.cos(self.beta), np.sin(self.beta)])
        re, im = np.linalg.solve(A, rhs)
        P = re + 1j * im
        q = np.zeros((H.size, 2), dtype=complex)
        q[H == 1] = np.array([P, -1j * P]) / 2
        q[H == -1] = np.conj(np.array([P, -1j * P]) / 2)
        return q


def assembled_reference(
    omega: float, M: dict, D: dict, K: dict, f: dict, H: np.ndarray
) -> np.ndarray:
    """Dense harmonic balance written from docs/conventions.md, solved by ``numpy.linalg.solve``.

    Row block ``m``, column block ``n``: ``-(n w1)^2 M_{m-n} + i n w1 D_{m-n} + K_{m-n}``.
    The coefficient dicts must hold both signs of every harmonic.
    """
    n_dof = next(iter(K.values())).shape[0]
    size = H.size * n_dof
    A = np.zeros((size, size), dtype=complex)
    b = np.zeros(size, dtype=complex)
    zero = np.zeros((n_dof, n_dof))
    for i, m in enumerate(H):
        rows = slice(i * n_dof, (i + 1) * n_dof)
        b[rows] = f.get(int(m), np.zeros(n_dof))
        for j, n in enumerate(H):
            k = int(m - n)
            s = 1j * n * omega
            A[rows, j * n_dof : (j + 1) * n_dof] = (
                s * s * M.get(k, zero) + s * D.get(k, zero) + K.get(k, zero)
            )
    return np.linalg.solve(A, b).reshape(H.size, n_dof)


def _jeffcott_unbalance(name: str, W: float, expect_unstable: bool, sparse: bool = False) -> Case:
    rotor = Jeffcott(W=W)
    assert rotor.unstable == expect_unstable, f"{name}: speed not where the case says"
    if expect_unstable:
        # A periodic solution exists but is not physical: never a success (docs/stability.md).
        converge: frozenset[str] = frozenset()
        fail = {
            "perturbation": frozenset({1, 2, 4}),
            "gmres": frozenset({4}),
            "direct": frozenset({4}),
        }
    else:
        converge, fail = frozenset({"perturbation", "gmres", "direct"}), {}
    return Case(
        name=name,
        system=lambda: rotor.system(sparse=sparse),
        harmonics=rl.HarmonicSet.full(5),
        reference=rotor.unbalance_response,
        converge=converge,
        fail=fail,
    )


# Unstable band of the default rotor: (k_x - W^2)(k_y - W^2) + c^2 W^2 < 0 for W in about
# (0.90, 1.09) rad/s.
JEFFCOTT_BELOW = 0.6
JEFFCOTT_INSIDE = 1.0
JEFFCOTT_ABOVE = 1.5


# --------------------------------------------------------------------------- gravity (DESIGN §3)
def gravity_rotor(sparse: bool = False, unbalance: bool = False, W_ratio: float = 0.5):
    """Asymmetric Jeffcott at ``W = W_ratio * sqrt(k_m/m)`` under gravity, ``eps = k_d/k_m = 0.2``,
    ``zeta = c / (2 sqrt(k_m m)) = 0.01``.

    At ``W_ratio = 0.5`` the static sag excites ``2W = sqrt(k_m/m)`` through ``K_{±2}``: the
    perturbation iteration's contraction factor is ``rho^2 = eps^2 / (2 zeta) = 2`` although the
    rotor is stable (far below its critical band).
    """
    km, m, eps, zeta = (2 * np.pi * 10) ** 2, 1.0, 0.2, 0.01
    wc = np.sqrt(km / m)
    return Jeffcott(
        W=W_ratio * wc,
        m=m,
        kx=km * (1 + eps),
        ky=km * (1 - eps),
        c=2 * zeta * np.sqrt(km * m),
        e=1e-3 if unbalance else 0.0,
        g=9.81,
    )


def _gravity_case(name: str, sparse: bool, unbalance: bool, W_ratio: float) -> Case:
    rotor = gravity_rotor(sparse=sparse, unbalance=unbalance, W_ratio=W_ratio)
    assert not rotor.unstable

    def reference(H: np.ndarray) -> np.ndarray:
        return assembled_reference(rotor.W, *rotor.coefficients(), H)

    diverges = W_ratio == 0.5
    return Case(
        name=name,
        system=lambda: rotor.system(sparse=sparse),
        harmonics=rl.HarmonicSet.full(16),
        reference=reference,
        converge=frozenset({"gmres", "direct"} | (set() if diverges else {"perturbation"})),
        fail={"perturbation": frozenset({1, 2})} if diverges else {},
        ref_tol=1e-8,
    )


# --------------------------------------------------------------------------- LTI chain
CHAIN_OMEGA = 3.0


def chain_coefficients() -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """Damped 3-DOF chain fixed at both ends, loads ``F1 cos(w1 t)`` on DOF 0 and
    ``F3 sin(3 w1 t)`` on DOF 2 (``sin = (e^{i} - e^{-i}) / 2i`` gives ``f_3 = -i F3 / 2``)."""
    m = np.array([1.0, 2.0, 1.5])
    k = np.array([100.0, 50.0, 80.0, 40.0])  # ground-0, 0-1, 1-2, 2-ground
    K = np.array(
        [[k[0] + k[1], -k[1], 0.0], [-k[1], k[1] + k[2], -k[2]], [0.0, -k[2], k[2] + k[3]]]
    )
    M = np.diag(m)
    D = 0.002 * K + 0.05 * M
    D[0, 1] -= 0.3  # a dashpot between DOF 0 and 1 (non-proportional)
    D[1, 0] -= 0.3
    D[0, 0] += 0.3
    D[1, 1] += 0.3
    f = {1: np.array([2.0, 0.0, 0.0]), 3: np.array([0.0, 0.0, -0.5j])}
    return M, D, K, f


def chain_reference(H: np.ndarray) -> np.ndarray:
    """``q_n = (-(n w)^2 M + i n w D + K)^{-1} f_n`` per frequency (numpy.linalg.solve)."""
    M, D, K, f = chain_coefficients()
    q = np.zeros((H.size, 3), dtype=complex)
    for i, n in enumerate(H):
        fn = f.get(abs(int(n)))
        if fn is None:
            continue
        fn = fn if n >= 0 else np.conj(fn)
        w = n * CHAIN_OMEGA
        q[i] = np.linalg.solve(-(w**2) * M + 1j * w * D + K, fn)
    return q


def chain_system(sparse: bool = False) -> rl.PeriodicSystem:
    M, D, K, f = chain_coefficients()
    conv = sp.csr_array if sparse else np.asarray
    return rl.PeriodicSystem(CHAIN_OMEGA, M={0: conv(M)}, D={0: conv(D)}, K={0: conv(K)}, f=f)


def _chain_case(name: str, sparse: bool) -> Case:
    return Case(
        name=name,
        system=lambda: chain_system(sparse),
        harmonics=rl.HarmonicSet.full(4),
        reference=chain_reference,
        converge=frozenset(METHODS),
        time_invariant=True,
    )


CASES: list[Case] = [
    _jeffcott_unbalance("jeffcott_unbalance_below", JEFFCOTT_BELOW, False),
    _jeffcott_unbalance("jeffcott_unbalance_inside_unstable", JEFFCOTT_INSIDE, True),
    _jeffcott_unbalance("jeffcott_unbalance_above", JEFFCOTT_ABOVE, False),
    _jeffcott_unbalance("jeffcott_unbalance_above_sparse", JEFFCOTT_ABOVE, False, sparse=True),
    _chain_case("chain3_lti", sparse=False),
    _chain_case("chain3_lti_sparse", sparse=True),
    _gravity_case("gravity_half_critical", sparse=False, unbalance=False, W_ratio=0.5),
    _gravity_case("gravity_half_critical_sparse", sparse=True, unbalance=False, W_ratio=0.5),
    _gravity_case("gravity_unbalance_0.3_critical", sparse=False, unbalance=True, W_ratio=0.3),
]


# --------------------------------------------------------------------------- time integration
def integrate(*args, **kwargs):
    """``scipy.integrate.solve_ivp`` with underflow tolerated.

    The autouse fixture turns every floating-point error into an exception (conftest.py);
    SciPy's step-size selection calls ``nextafter(t0, ...)`` at ``t0 = 0``, which underflows
    to a subnormal by design. Only the reference integrator gets this exemption.
    """
    from scipy.integrate import solve_ivp

    with np.errstate(under="ignore"):
        return solve_ivp(*args, **kwargs)
