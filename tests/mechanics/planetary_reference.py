"""Lin & Parker's planar lumped model of a planetary set, in the carrier frame: the reference
the planetary tests compare rheolin with. Written from the papers' equations, not from rheolin.

Sources (equation numbers of the papers):
* J. Lin, R. G. Parker, "Analytical characterization of the unique properties of planetary gear
  free vibration", J. Vib. Acoust. 121(3) 1999 316-321: coordinates (x, y, u = r theta) of the
  carrier, ring and sun in the carrier frame, (zeta, eta, u) of planet n along its radial and
  tangential directions; the mesh deflections
      delta_sn = -x_s sin(psi_sn) + y_s cos(psi_sn) - zeta_n sin(alpha_s) - eta_n cos(alpha_s)
                 + u_s + u_n,                                    psi_sn = psi_n - alpha_s
      delta_rn = -x_r sin(psi_rn) + y_r cos(psi_rn) + zeta_n sin(alpha_r) - eta_n cos(alpha_r)
                 + u_r - u_n,                                    psi_rn = psi_n + alpha_r
  the planet bearing deflections (radial, tangential)
      delta_cn = x_c cos(psi_n) + y_c sin(psi_n) - zeta_n,
      delta_cn' = -x_c sin(psi_n) + y_c cos(psi_n) + u_c - eta_n,
  the strain energy (1/2) sum k delta^2 with the central members' bearings k_j (x, y) and
  k_ju (u); the equations of motion with the carrier speed (eq. 6)
      M q'' + W_c G q' + (K_b + K_m - W_c^2 K_W) q = T,
  G = diag over members of 2 m [[0, -1, 0], [1, 0, 0], [0, 0, 0]], K_W = diag of (m, m, 0),
  M = diag of (m, m, I / r^2).
* J. Lin, R. G. Parker, "Planetary gear parametric instability caused by mesh stiffness
  variation", J. Sound Vib. 249(1) 2002 129-145, eqs. (1)-(3): the same equations with periodic
  mesh stiffnesses k_sn(t), k_rn(t).
* R. G. Parker, J. Lin, "Mesh phasing relationships in planetary and epicyclic gears", J. Mech.
  Des. 126(2) 2004 365-370: mesh n lags mesh 1 by gamma_sn = z_s psi_n / (2 pi) of a mesh
  period (sign by the direction of rotation), gamma_rn = -z_r psi_n / (2 pi).
Damping, not in the papers, is added where it physically acts: mesh damping on the rate of each
deflection, planet bearing damping on the rate of the bearing deflections (both in the carrier
frame), and the central members' bearing damping on their inertial velocity, which in the
carrier frame is q' + W_c [e]x q (Newton's law for a damper fixed in space).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

MEMBERS = ("c", "r", "s")


@dataclass
class LinParker:
    """Parameters (SI) of the planar model; every planet identical."""

    psi: np.ndarray  # planet angles [rad]
    alpha_s: float
    alpha_r: float
    m: dict[str, float]  # "c", "r", "s", "p"
    I_r2: dict[str, float]  # I / r^2 [kg] per member and "p"
    k: dict[str, float]  # bearing stiffness of "c", "r", "s" (x, y)
    ku: dict[str, float]  # torsional bearing (on u = r theta) of "c", "r", "s" [N/m]
    kp: float  # planet bearing (radial = tangential)
    ks: Callable[[float], np.ndarray]  # k_sn(t) for n = 0..N-1
    kr: Callable[[float], np.ndarray]
    c: dict[str, float] = field(default_factory=dict)  # bearing damping of "c", "r", "s"
    cu: dict[str, float] = field(default_factory=dict)
    cp: float = 0.0
    cs: float = 0.0  # mesh damping
    cr: float = 0.0
    es: Callable[[float], np.ndarray] | None = None  # static transmission error per mesh
    er: Callable[[float], np.ndarray] | None = None
    carrier_radius: float = 0.0  # r_c, for the planets' centrifugal load
    pin_errors: np.ndarray | None = None  # (N, 2): each pin's radial, tangential error [m]
    static: np.ndarray | None = None  # a constant generalized load (torques / r)

    @property
    def n_planets(self) -> int:
        return len(self.psi)

    @property
    def n(self) -> int:
        return 3 * (3 + self.n_planets)

    def index(self, member: str, n: int = 0) -> slice:
        """The (x, y, u) or (zeta, eta, u) coordinates of a member or of planet n."""
        i = MEMBERS.index(member) if member in MEMBERS else 3 + n
        return slice(3 * i, 3 * i + 3)

    def gradients(self) -> tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
        """d delta / d q of every sun mesh, ring mesh and planet bearing (radial, tangential)."""
        gs, gr, gb = [], [], []
        for n, psi in enumerate(self.psi):
            p = self.index("p", n)
            ps, pr = psi - self.alpha_s, psi + self.alpha_r
            g = np.zeros(self.n)
            g[self.index("s")] = [-np.sin(ps), np.cos(ps), 1.0]
            g[p] = [-np.sin(self.alpha_s), -np.cos(self.alpha_s), 1.0]
            gs.append(g)
            g = np.zeros(self.n)
            g[self.index("r")] = [-np.sin(pr), np.cos(pr), 1.0]
            g[p] = [np.sin(self.alpha_r), -np.cos(self.alpha_r), -1.0]
            gr.append(g)
            g = np.zeros(self.n)
            g[self.index("c")] = [np.cos(psi), np.sin(psi), 0.0]
            g[p] = [-1.0, 0.0, 0.0]
            gb.append(g)
            g = np.zeros(self.n)
            g[self.index("c")] = [-np.sin(psi), np.cos(psi), 1.0]
            g[p] = [0.0, -1.0, 0.0]
            gb.append(g)
        return gs, gr, gb

    def mass(self) -> np.ndarray:
        d = []
        for j in (*MEMBERS, *["p"] * self.n_planets):
            d += [self.m[j], self.m[j], self.I_r2[j]]
        return np.diag(d)

    def gyroscopic(self) -> tuple[np.ndarray, np.ndarray]:
        """``G`` and ``K_W`` (per unit ``W_c`` and ``W_c^2``)."""
        G = np.zeros((self.n, self.n))
        KW = np.zeros((self.n, self.n))
        for i, j in enumerate((*MEMBERS, *["p"] * self.n_planets)):
            s = slice(3 * i, 3 * i + 2)
            G[s, s] = 2 * self.m[j] * np.array([[0.0, -1.0], [1.0, 0.0]])
            KW[s, s] = self.m[j] * np.eye(2)
        return G, KW

    def bearings(self, omega_c: float) -> tuple[np.ndarray, np.ndarray]:
        """``K_b`` (with the circulatory term of the fixed dampers) and the damping ``C``."""
        K = np.zeros((self.n, self.n))
        C = np.zeros((self.n, self.n))
        for j in MEMBERS:
            s = self.index(j)
            K[s, s] += np.diag([self.k[j], self.k[j], self.ku[j]])
            cj = self.c.get(j, 0.0)
            C[s, s] += np.diag([cj, cj, self.cu.get(j, 0.0)])
            K[s.start : s.start + 2, s.start : s.start + 2] += (
                cj * omega_c * np.array([[0.0, -1.0], [1.0, 0.0]])
            )
        _, _, gb = self.gradients()
        for g in gb:
            K += self.kp * np.outer(g, g)
            C += self.cp * np.outer(g, g)
        return K, C

    def parts(self, omega_c: float) -> tuple[np.ndarray, ...]:
        """The constant ``M``, ``D``, ``K`` at carrier speed ``omega_c`` (meshes' damping in
        ``D``, their stiffness left out) and the mesh gradients' outer products."""
        G, KW = self.gyroscopic()
        Kb, Cb = self.bearings(omega_c)
        gs, gr, _ = self.gradients()
        S = np.array([np.outer(g, g) for g in gs])
        R = np.array([np.outer(g, g) for g in gr])
        D = Cb + omega_c * G + self.cs * S.sum(axis=0) + self.cr * R.sum(axis=0)
        return self.mass(), D, Kb - omega_c**2 * KW, S, R, np.array(gs), np.array(gr)

    def static_load(self, omega_c: float) -> np.ndarray:
        """The constant load: ``static``, each planet's centrifugal force ``m_p W_c^2 r_c``
        on its radial coordinate (its orbit needs it from the bearing; not in the papers), and
        the pin errors: a pin moved by ``epsilon`` leaves its bearing unloaded at
        ``delta_cn = -epsilon`` (Lin & Parker's bearing deflections are pin minus planet), so
        the energy ``k_p (delta + epsilon)^2 / 2`` loads ``-k_p epsilon grad(delta)``."""
        f = np.zeros(self.n) if self.static is None else np.array(self.static, dtype=float)
        for n in range(self.n_planets):
            f[self.index("p", n).start] += self.m["p"] * omega_c**2 * self.carrier_radius
        if self.pin_errors is not None:
            _, _, gb = self.gradients()
            for n, (er, et) in enumerate(np.asarray(self.pin_errors, dtype=float)):
                f -= self.kp * (er * gb[2 * n] + et * gb[2 * n + 1])
        return f

    def matrices(self, t: float, omega_c: float) -> tuple[np.ndarray, ...]:
        """``M, D, K`` and the load at time ``t``."""
        M, D, K0, S, R, gs, gr = self.parts(omega_c)
        ks, kr = self.ks(t), self.kr(t)
        K = K0 + np.tensordot(ks, S, 1) + np.tensordot(kr, R, 1)
        f = self.static_load(omega_c)
        if self.es is not None:
            f += (ks * self.es(t)) @ gs
        if self.er is not None:
            f += (kr * self.er(t)) @ gr
        return M, D, K, f

    def state_function(self, omega_c: float) -> Callable[[float], np.ndarray]:
        """``t -> A(t)`` of the first-order system, the constant parts computed once."""
        M, D, K0, S, R, _, _ = self.parts(omega_c)
        Mi = np.linalg.inv(M)
        MiS, MiR = Mi @ S, Mi @ R
        top = np.hstack([np.zeros_like(M), np.eye(self.n)])

        def A(t: float) -> np.ndarray:
            Kt = Mi @ K0 + np.tensordot(self.ks(t), MiS, 1) + np.tensordot(self.kr(t), MiR, 1)
            return np.vstack([top, np.hstack([-Kt, -Mi @ D])])

        return A

    def state_matrix(self, t: float, omega_c: float) -> np.ndarray:
        M, D, K, _ = self.matrices(t, omega_c)
        Mi = np.linalg.inv(M)
        z = np.zeros_like(M)
        return np.block([[z, np.eye(self.n)], [-Mi @ K, -Mi @ D]])


def monodromy(
    state: Callable[[float], np.ndarray], period: float, n: int, repeat: int = 1
) -> np.ndarray:
    """The state-transition matrix over ``period`` of ``x' = A(t) x`` (DOP853 on the matrix
    ODE, tolerances near round-off), for ``A`` of period ``period / repeat``: one such period
    integrated, raised to the power ``repeat``."""

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        return (state(t) @ x.reshape(n, n)).ravel()

    with np.errstate(under="ignore"):  # SciPy's smallest step at t = 0
        sol = solve_ivp(
            rhs,
            (0.0, period / repeat),
            np.eye(n).ravel(),
            method="DOP853",
            rtol=1e-11,
            atol=1e-13,
        )
    return np.linalg.matrix_power(sol.y[:, -1].reshape(n, n), repeat)
