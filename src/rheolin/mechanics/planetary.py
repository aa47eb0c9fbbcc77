"""Planetary gear sets: geometry, assembly checks, lines of action and mesh phasing.

A simple planetary set has a sun, a ring and a carrier on one axis ``e``, and ``N`` planets
whose centres sit on the carrier at radius ``r_c`` and angles ``psi_n`` (right-handed about
``e`` from a reference direction ``a``). Everything here is written in the carrier's axes at
``t = 0`` (which are the global axes then, as for every rotating body in rheolin): planet ``n``
has the radial and tangential unit vectors ``r_n = cos(psi_n) a + sin(psi_n) b`` and
``t_n = e x r_n`` with ``b = e x a``.

Meshes (Lin & Parker, J. Sound Vib. 249(1) 2002, eqs. 1-3, written in three dimensions). With
the flank ``sigma = +1`` when the sun pushes the planets forward (``+t_n``), the transverse lines
of action at the working pressure angles ``alpha_s``, ``alpha_r`` are::

    n_s = sigma cos(alpha_s) t_n + sin(alpha_s) r_n     (sun on planet)
    n_r = sigma cos(alpha_r) t_n - sin(alpha_r) r_n     (ring on planet)

tilted by the base helix angle ``beta_b`` to ``cos(beta_b) n + sigma sin(beta_b) e`` (sun) and
``... - sigma sin(beta_b) e`` (ring: the two axial thrusts on a planet cancel). The mesh
deflection is ``delta = w^T (q_member, q_planet)`` with the 12-vector
``w = (n, (P - x_m) x n, -n, -(P - p_n) x n)`` of :func:`~rheolin.mechanics.gears.line_of_action`,
``P`` the contact point on the line of action; in the plane this is Lin & Parker's
``delta_sn = -x_s sin(psi_n - alpha_s) + y_s cos(psi_n - alpha_s) - zeta_n sin(alpha_s)
- eta_n cos(alpha_s) + u_s + u_n`` and ``delta_rn = ... + zeta_n sin(alpha_r) - eta_n
cos(alpha_r) + u_r - u_n``.

Mesh phasing (Parker & Lin, J. Mech. Des. 126(2) 2004): the sun's tooth pattern passes planet
``n`` a time ``psi_n / (W_s - W_c)`` after it passes planet 0, so the stiffness and transmission
error of sun mesh ``n`` are those of mesh 0 delayed by the mesh phase
``gamma_sn = sign(W_s - W_c) z_s psi_n`` [rad of the mesh cycle]; for the ring,
``gamma_rn = sign(W_r - W_c) z_r psi_n`` plus the ring-to-sun phase of one planet (a property of
the tooth geometry, given). A set assembles when every ``(z_s + z_r) psi_n / (2 pi)`` is an
integer; then ``gamma_rn = gamma_sn`` modulo a full mesh cycle.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from .rotation import unit_axis

__all__ = [
    "CENTRE_TOLERANCE",
    "PlanetContact",
    "PlanetaryGeometry",
    "check_members",
    "equal_spacing",
    "mesh_phases",
    "phased",
    "planet_directions",
]

#: Sun-planet and ring-planet centre distances, and a given carrier radius, may differ from
#: the standard ones by this fraction (profile shifts); more is a modelling error.
CENTRE_TOLERANCE = 0.03
#: ``(z_s + z_r) psi_n / (2 pi)`` within this of an integer assembles.
ASSEMBLY_TOLERANCE = 1e-6


def equal_spacing(planets: int) -> tuple[float, ...]:
    """Angles [rad] of ``planets`` equally spaced planets, the first at 0.

    >>> [round(a, 6) for a in equal_spacing(3)]
    [0.0, 2.094395, 4.18879]
    """
    if isinstance(planets, bool) or not isinstance(planets, int | np.integer) or planets < 1:
        raise ModelError(f"`planets` must be a positive integer, got {planets!r}")
    return tuple(2 * math.pi * n / int(planets) for n in range(int(planets)))


def _teeth(value: object, field: str, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < least:
        raise ModelError(f"`{field}` must be an integer >= {least}, got {value!r}")
    return int(value)


def _positive(value: object, field: str) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ModelError(f"`{field}` must be a positive number, got {value!r}") from None
    if not np.isfinite(v) or v <= 0:
        raise ModelError(f"`{field}` must be a positive finite number, got {value!r}")
    return v


@dataclass(frozen=True)
class PlanetContact:
    """The meshes and bearing of one planet, in the carrier's axes at ``t = 0``.

    Attributes
    ----------
    angle
        ``psi_n`` [rad].
    position
        Planet centre ``p_n`` [m].
    radial, tangential
        ``r_n`` and ``t_n``.
    sun, ring
        The 12-vectors ``w`` of the sun-planet and ring-planet meshes over (member node,
        planet node): ``delta = w^T (q_member, q_planet)``.
    """

    angle: float
    position: np.ndarray
    radial: np.ndarray
    tangential: np.ndarray
    sun: np.ndarray
    ring: np.ndarray


@dataclass(frozen=True)
class PlanetaryGeometry:
    """Tooth counts, planet angles and gear geometry of a simple planetary set, checked.

    Parameters
    ----------
    sun_teeth, planet_teeth, ring_teeth
        Tooth counts.
    planet_angles
        ``psi_n`` [rad], increasing in ``[0, 2 pi)``.
    module, pressure_angle, helix_angle
        Normal module [m], normal pressure angle [rad] and the sun's helix angle [rad] (its
        sign is the hand; planets have the other hand, the ring the planets').
    carrier_radius
        Radius of the planet centres [m]; default the standard sun-planet centre distance.

    Raises
    ------
    ModelError
        Tooth counts that do not assemble at the given angles, a ring smaller than the sun
        plus two planets, centre distances more than :data:`CENTRE_TOLERANCE` apart, planets
        whose tip circles overlap.

    Examples
    --------
    The 750 kW NREL GRC planetary stage, 21/39/99 teeth, three planets:

    >>> g = PlanetaryGeometry(21, 39, 99, equal_spacing(3), 0.010, np.radians(20),
    ...                       np.radians(7.5))
    >>> round(g.carrier_radius, 6), round(float(np.degrees(g.sun_pressure_angle)), 4)
    (0.302589, 20.1587)
    >>> PlanetaryGeometry(21, 39, 98, equal_spacing(3), 0.010, np.radians(20))
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rheolin.errors.ModelError: `ring_teeth`: 98 teeth: a ring smaller than the sun plus two ...
    """

    sun_teeth: int
    planet_teeth: int
    ring_teeth: int
    planet_angles: tuple[float, ...]
    module: float
    pressure_angle: float
    helix_angle: float = 0.0
    carrier_radius: float = 0.0

    def __post_init__(self) -> None:
        zs = _teeth(self.sun_teeth, "sun_teeth", 3)
        zp = _teeth(self.planet_teeth, "planet_teeth", 3)
        zr = _teeth(self.ring_teeth, "ring_teeth", 3)
        m = _positive(self.module, "module")
        alpha = float(self.pressure_angle)
        if not 0 < alpha < np.pi / 2:
            raise ModelError(f"`pressure_angle` must lie in (0, 90) deg, got {alpha!r} rad")
        beta = float(self.helix_angle)
        if not abs(beta) < np.pi / 2:
            raise ModelError(f"`helix_angle` must lie in (-90, 90) deg, got {beta!r} rad")
        if zr < zs + 2 * zp:
            raise ModelError(
                f"`ring_teeth`: {zr} teeth: a ring smaller than the sun plus two planets "
                f"({zs} + 2 x {zp} = {zs + 2 * zp}) cannot hold them"
            )
        mt = m / np.cos(beta)
        a_sun, a_ring = mt * (zs + zp) / 2, mt * (zr - zp) / 2
        if abs(a_ring - a_sun) > CENTRE_TOLERANCE * a_sun:
            raise ModelError(
                f"`ring_teeth`: {zr} teeth put the planets at {a_ring * 1e3:.6g} mm from the "
                f"ring centre but {a_sun * 1e3:.6g} mm from the sun's (more than "
                f"{CENTRE_TOLERANCE:.0%} apart); a standard set has z_r = z_s + 2 z_p = "
                f"{zs + 2 * zp}"
            )
        rc = float(self.carrier_radius) or float(a_sun)
        if not np.isfinite(rc) or abs(rc - a_sun) > CENTRE_TOLERANCE * a_sun:
            raise ModelError(
                f"`carrier_radius` {rc!r} m must lie within {CENTRE_TOLERANCE:.0%} of the "
                f"sun-planet centre distance {a_sun:.6g} m"
            )
        angles = self._angles(zs + zr)
        for name, v in (("sun_teeth", zs), ("planet_teeth", zp), ("ring_teeth", zr)):
            object.__setattr__(self, name, v)
        object.__setattr__(self, "module", m)
        object.__setattr__(self, "pressure_angle", alpha)
        object.__setattr__(self, "helix_angle", beta)
        object.__setattr__(self, "carrier_radius", rc)
        object.__setattr__(self, "planet_angles", angles)
        for name, r in (("sun", self.sun_pressure_angle), ("ring", self.ring_pressure_angle)):
            if not 0 < r < np.pi / 2:
                raise ModelError(
                    f"`carrier_radius` {rc:.6g} m leaves no working pressure angle for the "
                    f"{name}-planet mesh (base radii too large for it)"
                )
        self._check_clearance()

    def _angles(self, sum_teeth: int) -> tuple[float, ...]:
        raw = np.asarray(self.planet_angles, dtype=float).ravel()
        if raw.size < 1 or not np.all(np.isfinite(raw)):
            raise ModelError(f"`planet_angles` must be finite angles, got {self.planet_angles!r}")
        a = np.mod(raw, 2 * np.pi)
        if np.any(np.diff(a) <= 0):
            raise ModelError("`planet_angles` must increase within one turn (0 to 360 deg)")
        n = a.size
        equal = np.allclose(a - a[0], 2 * np.pi * np.arange(n) / n, atol=1e-9)
        for i, psi in enumerate(a):
            turns = sum_teeth * (psi - a[0]) / (2 * np.pi)
            if abs(turns - round(turns)) > ASSEMBLY_TOLERANCE:
                if equal:
                    raise ModelError(
                        f"`ring_teeth`: {n} equally spaced planets do not assemble: "
                        f"(z_s + z_r) / N = {sum_teeth}/{n} is not an integer (choose tooth "
                        "counts whose sum is a multiple of the planets, or `planet_angles`)"
                    )
                near = a[0] + 2 * np.pi * round(turns) / sum_teeth
                raise ModelError(
                    f"`planet_angles[{i}]`: {np.degrees(psi):.6g} deg does not assemble: "
                    f"(z_s + z_r) psi / 360 deg = {turns:.6g} must be an integer (nearest: "
                    f"{np.degrees(near):.6g} deg)"
                )
        return tuple(float(x) for x in a)

    def _check_clearance(self) -> None:
        """Adjacent planets' tip circles (addendum one normal module) must not overlap."""
        a = np.asarray(self.planet_angles)
        if a.size < 2:
            return
        gaps = np.diff(np.append(a, a[0] + 2 * np.pi))
        tip = self.transverse_module * self.planet_teeth + 2 * self.module
        chord = 2 * self.carrier_radius * np.sin(gaps / 2)
        i = int(np.argmin(chord))
        if chord[i] <= tip:
            j = (i + 1) % a.size
            raise ModelError(
                f"`planet_angles`: planets {i} and {j} ({np.degrees(gaps[i]):.6g} deg apart) "
                f"collide: their centres are {chord[i] * 1e3:.6g} mm apart, less than the "
                f"planet tip diameter {tip * 1e3:.6g} mm"
            )

    # ------------------------------------------------------------------ derived geometry
    @property
    def planets(self) -> int:
        """Number of planets ``N``."""
        return len(self.planet_angles)

    @property
    def equally_spaced(self) -> bool:
        """True when the planets are ``2 pi / N`` apart."""
        a = np.asarray(self.planet_angles)
        n = a.size
        return bool(np.allclose(a - a[0], 2 * np.pi * np.arange(n) / n, atol=1e-9))

    @property
    def transverse_module(self) -> float:
        """``m / cos(beta)`` [m]."""
        return self.module / float(np.cos(self.helix_angle))

    @property
    def transverse_pressure_angle(self) -> float:
        """``arctan(tan(alpha_n) / cos(beta))`` [rad] (generating)."""
        return float(np.arctan(np.tan(self.pressure_angle) / np.cos(self.helix_angle)))

    @property
    def base_helix_angle(self) -> float:
        """``arctan(tan(beta) cos(alpha_t))`` [rad], signed as the sun's helix."""
        return float(np.arctan(np.tan(self.helix_angle) * np.cos(self.transverse_pressure_angle)))

    def base_radius(self, teeth: int) -> float:
        """Base radius [m] of a gear of this set with ``teeth`` teeth."""
        return float(self.transverse_module * teeth / 2 * np.cos(self.transverse_pressure_angle))

    @property
    def sun_pressure_angle(self) -> float:
        """Working transverse pressure angle of the sun-planet meshes [rad]."""
        c = (self.base_radius(self.sun_teeth) + self.base_radius(self.planet_teeth)) / (
            self.carrier_radius
        )
        return float(np.arccos(c)) if c < 1 else 0.0

    @property
    def ring_pressure_angle(self) -> float:
        """Working transverse pressure angle of the ring-planet meshes [rad]."""
        c = (self.base_radius(self.ring_teeth) - self.base_radius(self.planet_teeth)) / (
            self.carrier_radius
        )
        return float(np.arccos(c)) if c < 1 else 0.0

    def contacts(
        self,
        axis: object,
        reference: object,
        centre: object,
        sun_node: object,
        ring_node: object,
        flank: int = 1,
    ) -> list[PlanetContact]:
        """Planet centres and mesh vectors, in the carrier's axes at ``t = 0``.

        Parameters
        ----------
        axis
            The set's axis ``e`` (the carrier's spin axis).
        reference
            The direction of angle 0 (projected onto the plane normal to ``axis``).
        centre
            A point on the axis in the planets' plane [m].
        sun_node, ring_node
            Positions of the sun and ring nodes [m] (their lever arms to the contacts).
        flank
            ``sigma``: +1 when the sun pushes the planets forward, -1 the other flank.

        Examples
        --------
        Spur set about z, planet 0 on x: the sun mesh of planet 0 is Lin & Parker's
        ``(-sin(psi - alpha), cos(psi - alpha), r_bs)`` on the sun's ``(x, y, phiz)``.

        >>> g = PlanetaryGeometry(20, 20, 60, equal_spacing(4), 0.002, np.radians(20))
        >>> c = g.contacts([0, 0, 1], [1, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0])
        >>> w = c[0].sun
        >>> bool(np.allclose(w[[0, 1, 5]], [np.sin(np.radians(20)), np.cos(np.radians(20)),
        ...                                   g.base_radius(20)]))
        True
        """
        if flank not in (1, -1):
            raise ModelError(f"`side` must be +1 or -1, got {flank!r}")
        e = unit_axis(axis)
        o = np.asarray(centre, dtype=float).reshape(3)
        xs = np.asarray(sun_node, dtype=float).reshape(3)
        xr = np.asarray(ring_node, dtype=float).reshape(3)
        rbs, rbr = self.base_radius(self.sun_teeth), self.base_radius(self.ring_teeth)
        bb = self.base_helix_angle
        out = []
        for psi in self.planet_angles:
            r, t = planet_directions(e, reference, psi)
            p = o + self.carrier_radius * r
            a_s, a_r = self.sun_pressure_angle, self.ring_pressure_angle
            ns_t = flank * np.cos(a_s) * t + np.sin(a_s) * r
            nr_t = flank * np.cos(a_r) * t - np.sin(a_r) * r
            ps = o + rbs * flank * np.cross(ns_t, e)  # tangency with the sun's base circle
            pr = o + rbr * flank * np.cross(nr_t, e)  # ... and with the ring's
            ns = np.cos(bb) * ns_t + flank * np.sin(bb) * e
            nr = np.cos(bb) * nr_t - flank * np.sin(bb) * e
            w_s = np.concatenate([ns, np.cross(ps - xs, ns), -ns, -np.cross(ps - p, ns)])
            w_r = np.concatenate([nr, np.cross(pr - xr, nr), -nr, -np.cross(pr - p, nr)])
            out.append(PlanetContact(float(psi), p, r, t, w_s, w_r))
        return out


def planet_directions(axis: object, reference: object, angle: float) -> tuple[np.ndarray, ...]:
    """Radial and tangential unit vectors ``(r, t)`` at ``angle`` [rad] about ``axis`` from the
    projection of ``reference`` onto the plane normal to it.

    >>> r, t = planet_directions([0, 0, 1], [1, 0, 0], np.pi / 2)
    >>> np.round(r, 12) + 0.0, np.round(t, 12) + 0.0
    (array([0., 1., 0.]), array([-1.,  0.,  0.]))
    """
    e = unit_axis(axis)
    a = np.asarray(reference, dtype=float).reshape(3)
    a = a - (a @ e) * e
    if np.linalg.norm(a) < 1e-9:
        raise ModelError("`angle_reference` must not be parallel to the set's axis")
    a = a / np.linalg.norm(a)
    b = np.cross(e, a)
    r = np.cos(angle) * a + np.sin(angle) * b
    return r, np.cross(e, r)


def mesh_phases(
    geometry: PlanetaryGeometry,
    sun_relative: int,
    ring_phase: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Mesh phases ``(gamma_s, gamma_r)`` [rad of the mesh cycle] of every planet's meshes.

    Parameters
    ----------
    geometry
        The set.
    sun_relative
        Sign of ``W_s - W_c`` (the ring turns the other way relative to the carrier); 0 when
        the set turns as one block (no tooth passes: phases 0).
    ring_phase
        Phase of planet 0's ring mesh relative to its sun mesh [rad of the mesh cycle].

    Examples
    --------
    23/25/73 teeth (Parker & Lin's example spacing), four planets 90 deg apart:

    >>> g = PlanetaryGeometry(23, 25, 73, equal_spacing(4), 0.002, np.radians(20))
    >>> s, r = mesh_phases(g, 1)
    >>> np.round(s / (2 * np.pi), 4), bool(np.allclose(np.exp(1j * s), np.exp(1j * r)))
    (array([0.  , 0.75, 0.5 , 0.25]), True)
    """
    sign = int(np.sign(sun_relative))
    psi = np.asarray(geometry.planet_angles) - geometry.planet_angles[0]
    gs = np.mod(sign * geometry.sun_teeth * psi, 2 * np.pi)
    gr = np.mod(-sign * geometry.ring_teeth * psi + float(ring_phase), 2 * np.pi)
    return gs, gr


def phased(coefficients: Mapping[int, complex], phase: float) -> dict[int, complex]:
    """Coefficients of ``x(t - tau)`` from those of ``x(t)`` with ``W_m tau = phase``:
    ``x_j exp(-i j phase)``.

    >>> c = phased({0: 1.0, 1: 0.5, -1: 0.5}, np.pi / 2)
    >>> {j: complex(np.round(v, 12) + 0) for j, v in c.items()}
    {0: (1+0j), 1: -0.5j, -1: 0.5j}
    """
    return {int(j): complex(c) * complex(np.exp(-1j * j * phase)) for j, c in coefficients.items()}


def check_members(axes: Sequence[object], positions: Sequence[object]) -> np.ndarray:
    """The common axis of the sun, ring and carrier nodes; refused when their axes differ or
    a node lies off the carrier's axis line."""
    names = ("sun", "ring", "carrier")
    e = unit_axis(axes[2], "carrier axis")
    for name, a in zip(names, axes, strict=True):
        if float(unit_axis(a) @ e) < 1 - 1e-9:
            raise ModelError(
                f"`{name}_body`: its axis must be the carrier's ({np.round(e, 6).tolist()}), "
                "pointing the same way"
            )
    xc = np.asarray(positions[2], dtype=float)
    for name, x in zip(names, positions, strict=True):
        d = np.asarray(x, dtype=float) - xc
        off = d - (d @ e) * e
        if np.linalg.norm(off) > 1e-9 * max(1.0, float(np.linalg.norm(d))):
            raise ModelError(
                f"`{name}_node` lies {np.linalg.norm(off) * 1e3:.6g} mm off the carrier's axis"
            )
    return e
