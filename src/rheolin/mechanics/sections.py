"""Beam cross-sections and materials.

Section axes: local ``x`` along the beam, ``y`` and ``z`` the section's principal axes.
``Iy``, ``Iz`` are the second moments about ``y`` and ``z`` (``Iz`` resists bending in the x-y
plane). Shear factors ``kappa_y``, ``kappa_z`` (Timoshenko) apply to shear along ``y`` and ``z``.
Shear factors of the closed-form sections follow Cowper (1966) and depend on Poisson's ratio.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ModelError

__all__ = [
    "Material",
    "Section",
    "element_materials",
    "general_section",
    "hollow_circular",
    "rectangular",
    "solid_circular",
]


def _positive(name: str, value: float, allow_zero: bool = False) -> float:
    v = float(value)
    if not np.isfinite(v) or v < 0.0 or (v == 0.0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ModelError(f"`{name}` must be finite and {bound}, got {value!r}")
    return v


@dataclass(frozen=True)
class Material:
    """Linear elastic material.

    Parameters
    ----------
    E
        Young's modulus [Pa].
    density
        Mass density ``rho`` [kg/m^3].
    G, nu
        Shear modulus [Pa] or Poisson's ratio; give exactly one (``G = E / (2 (1 + nu))``).
    damping_beta
        Rotating material damping, stiffness proportional: ``D_B = beta K_B`` [s].
        A loss factor ``eta`` at a reference frequency ``w_ref`` is ``beta = eta / w_ref``
        (see :meth:`with_loss_factor`).

    Examples
    --------
    >>> steel = Material(E=210e9, density=7850.0, nu=0.3)
    >>> round(steel.G / 1e9, 3), steel.nu
    (80.769, 0.3)
    """

    E: float
    density: float
    G: float | None = None
    nu: float | None = None
    damping_beta: float = 0.0

    def __post_init__(self) -> None:
        E = _positive("E", self.E)
        rho = _positive("density", self.density, allow_zero=True)
        if (self.G is None) == (self.nu is None):
            raise ModelError("give exactly one of `G` and `nu` for a Material")
        if self.G is not None:
            G = _positive("G", self.G)
            nu = E / (2.0 * G) - 1.0
        else:
            nu = float(self.nu)  # type: ignore[arg-type]
            if not -1.0 < nu < 0.5:
                raise ModelError(f"`nu` must lie in (-1, 0.5), got {self.nu!r}")
            G = E / (2.0 * (1.0 + nu))
        object.__setattr__(self, "E", E)
        object.__setattr__(self, "density", rho)
        object.__setattr__(self, "G", G)
        object.__setattr__(self, "nu", nu)
        object.__setattr__(self, "damping_beta", _positive("damping_beta", self.damping_beta, True))

    def with_loss_factor(self, eta: float, omega_ref: float) -> Material:
        """Copy with ``damping_beta = eta / omega_ref`` (viscous equivalent of a loss factor).

        >>> Material(E=1.0, density=1.0, nu=0.3).with_loss_factor(0.02, 100.0).damping_beta
        0.0002
        """
        beta = _positive("eta", eta, True) / _positive("omega_ref", omega_ref)
        return Material(E=self.E, density=self.density, G=self.G, damping_beta=beta)


@dataclass(frozen=True)
class Section:
    """Cross-section properties in the section's principal axes.

    Parameters
    ----------
    area
        Area ``A`` [m^2].
    Iy, Iz
        Second moments of area about local ``y`` and ``z`` [m^4].
    torsion_constant
        Saint-Venant torsion constant ``J_t`` [m^4] (``= Iy + Iz`` for circular sections).
    kappa_y, kappa_z
        Timoshenko shear factors for shear along ``y`` and ``z``; ``inf`` means shear-rigid
        (Euler–Bernoulli / Rayleigh).
    """

    area: float
    Iy: float
    Iz: float
    torsion_constant: float
    kappa_y: float = np.inf
    kappa_z: float = np.inf

    def __post_init__(self) -> None:
        for name in ("area", "Iy", "Iz", "torsion_constant", "kappa_y", "kappa_z"):
            v = float(getattr(self, name))
            if np.isnan(v) or v <= 0.0:
                raise ModelError(f"section `{name}` must be > 0, got {getattr(self, name)!r}")
            if name not in ("kappa_y", "kappa_z") and not np.isfinite(v):
                raise ModelError(f"section `{name}` must be finite, got {v!r}")
            object.__setattr__(self, name, v)

    @property
    def polar(self) -> float:
        """Polar second moment ``Iy + Iz`` (rotary inertia about the beam axis per rho)."""
        return self.Iy + self.Iz

    @property
    def axisymmetric(self) -> bool:
        """True when both bending planes are identical (rotation invariant about the axis)."""
        same_kappa = self.kappa_y == self.kappa_z or np.isclose(self.kappa_y, self.kappa_z)
        return bool(np.isclose(self.Iy, self.Iz, rtol=1e-12) and same_kappa)


def general_section(
    area: float,
    Iy: float,
    Iz: float,
    torsion_constant: float,
    kappa_y: float = np.inf,
    kappa_z: float = np.inf,
) -> Section:
    """Section from its properties (non-axisymmetric shafts: keyway, flats: ``Iy != Iz``).

    >>> general_section(1e-3, 2e-7, 1e-7, 2.5e-7).axisymmetric
    False
    """
    return Section(area, Iy, Iz, torsion_constant, kappa_y, kappa_z)


def solid_circular(diameter: float, nu: float = 0.3) -> Section:
    """Solid circular section, Cowper shear factor ``6 (1 + nu) / (7 + 6 nu)``.

    >>> s = solid_circular(0.02)
    >>> round(s.area * 1e6, 4), round(s.kappa_y, 5), s.axisymmetric
    (314.1593, 0.88636, True)
    """
    d = _positive("diameter", diameter)
    kappa = 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu)
    I = np.pi * d**4 / 64.0
    return Section(np.pi * d**2 / 4.0, I, I, 2.0 * I, kappa, kappa)


def hollow_circular(outer_diameter: float, inner_diameter: float, nu: float = 0.3) -> Section:
    """Hollow circular (tube) section, Cowper shear factor.

    >>> s = hollow_circular(0.04, 0.02)
    >>> round(s.Iy / 1e-8, 4)
    11.781
    """
    Do = _positive("outer_diameter", outer_diameter)
    di = _positive("inner_diameter", inner_diameter, allow_zero=True)
    if di >= Do:
        raise ModelError(f"`inner_diameter` must be < outer_diameter, got {inner_diameter!r}")
    m = di / Do
    kappa = (
        6.0
        * (1.0 + nu)
        * (1.0 + m**2) ** 2
        / ((7.0 + 6.0 * nu) * (1.0 + m**2) ** 2 + (20.0 + 12.0 * nu) * m**2)
    )
    I = np.pi * (Do**4 - di**4) / 64.0
    return Section(np.pi * (Do**2 - di**2) / 4.0, I, I, 2.0 * I, kappa, kappa)


def rectangular(width_y: float, height_z: float, nu: float = 0.3) -> Section:
    """Rectangular section ``width_y`` along local y, ``height_z`` along local z.

    Shear factor ``10 (1 + nu) / (12 + 11 nu)``; torsion constant from the series
    approximation ``a b^3 (1/3 - 0.21 (b/a) (1 - b^4 / (12 a^4)))``, ``a >= b``.

    >>> s = rectangular(0.02, 0.01)
    >>> round(s.Iz / s.Iy, 6)
    4.0
    """
    b_y = _positive("width_y", width_y)
    h_z = _positive("height_z", height_z)
    a, b = max(b_y, h_z), min(b_y, h_z)
    Jt = a * b**3 * (1.0 / 3.0 - 0.21 * (b / a) * (1.0 - b**4 / (12.0 * a**4)))
    kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)
    return Section(b_y * h_z, b_y * h_z**3 / 12.0, h_z * b_y**3 / 12.0, Jt, kappa, kappa)


def element_materials(
    n: int,
    elastic_modulus: object,
    density: object,
    poisson_ratio: object | None = None,
    shear_modulus: object | None = None,
    damping_beta: float = 0.0,
) -> list[Material]:
    """One :class:`Material` per element from values given per shaft or per element.

    Give ``poisson_ratio`` or ``shear_modulus`` (not both); neither means ``nu = 0.3``.

    >>> [m.G for m in element_materials(2, 2e11, 7800.0, shear_modulus=[8e10, 7e10])]
    [80000000000.0, 70000000000.0]
    """

    def each(value: object, name: str) -> np.ndarray:
        a = np.asarray(value, dtype=float).ravel()
        if a.size == 1:
            a = np.full(n, a[0])
        if a.size != n:
            raise ModelError(f"`{name}` must be one value or one per element ({n}), got {a.size}")
        return a

    if poisson_ratio is not None and shear_modulus is not None:
        raise ModelError("give `poisson_ratio` or `shear_modulus`, not both")
    E, rho = each(elastic_modulus, "elastic_modulus"), each(density, "density")
    if shear_modulus is not None:
        G = each(shear_modulus, "shear_modulus")
        return [
            Material(E=e, density=r, G=g, damping_beta=damping_beta)
            for e, r, g in zip(E, rho, G, strict=True)
        ]
    nu = each(0.3 if poisson_ratio is None else poisson_ratio, "poisson_ratio")
    return [
        Material(E=e, density=r, nu=v, damping_beta=damping_beta)
        for e, r, v in zip(E, rho, nu, strict=True)
    ]


#: Materials a model may name instead of giving the constants (``material="steel"``):
#: elastic modulus [Pa], Poisson's ratio, density [kg/m^3]. Explicit values override them.
MATERIALS: dict[str, dict[str, float]] = {
    "steel": {"elastic_modulus": 2.1e11, "poisson_ratio": 0.3, "density": 7850.0},
    "stainless_steel": {"elastic_modulus": 1.93e11, "poisson_ratio": 0.29, "density": 8000.0},
    "cast_iron": {"elastic_modulus": 1.1e11, "poisson_ratio": 0.26, "density": 7200.0},
    "aluminium": {"elastic_modulus": 7.0e10, "poisson_ratio": 0.33, "density": 2700.0},
    "titanium": {"elastic_modulus": 1.14e11, "poisson_ratio": 0.34, "density": 4430.0},
}


def material_constants(material: str | None, keys: Mapping[str, Any], where: str) -> dict[str, Any]:
    """``keys`` (name -> value or None) with the missing ones from the named ``material``.

    rheolin assumes no material: a constant that is neither given nor named is refused.
    ``poisson_ratio`` is not needed when ``shear_modulus`` is given.

    >>> material_constants("steel", {"elastic_modulus": 2e11, "density": None}, "add_shaft")
    {'elastic_modulus': 200000000000.0, 'density': 7850.0}
    >>> material_constants(None, {"density": None}, "add_disk")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rheolin.errors.ModelError: add_disk: `density` is required (or name a material, ...
    """
    if material is not None and material not in MATERIALS:
        raise ModelError(
            f"{where}: `material` must be one of {', '.join(MATERIALS)}, got {material!r}"
        )
    out: dict[str, Any] = {}
    for key, value in keys.items():
        if value is None and material is not None:
            value = MATERIALS[material][key]
        if value is None:
            raise ModelError(
                f"{where}: `{key}` is required (or name a material, material='steel'; known: "
                f"{', '.join(MATERIALS)}); rheolin assumes no material"
            )
        out[key] = float(value) if isinstance(value, int | float) else value
    return out
