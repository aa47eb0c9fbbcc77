"""Shaft elements made of concentric layers: uniform or conical tubes, each with its material.

An element of a shaft is one or more :class:`ShaftLayer` between the same two nodes (a shaft
with a shrunk-on sleeve, an impeller hub modelled as a mass-only layer, ...). The layers act in
parallel: the element's matrices are the sum of each layer's Timoshenko matrices, every layer
with its own shear parameter (as ROSS does for elements sharing a node).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ModelError
from .beam import BeamMatrices, beam_body_matrices
from .conical import conical_body_matrices
from .rotation import unit_axis
from .sections import (
    Material,
    Section,
    element_materials,
    hollow_circular,
    material_constants,
    solid_circular,
)

__all__ = [
    "ShaftLayer",
    "circular_layer",
    "element_matrices",
    "layer_elements",
    "shaft_layers",
    "shaft_materials",
    "shaft_nodes",
    "tube_layers",
]


@dataclass(frozen=True)
class ShaftLayer:
    """One layer of a shaft element: a ``section`` (uniform) or conical tube ``diameters``
    ``(outer_left, inner_left, outer_right, inner_right)`` [m], and its material."""

    material: Material
    section: Section | None = None
    diameters: tuple[float, float, float, float] | None = None


def circular_layer(
    material: Material,
    outer: float,
    inner: float = 0.0,
    outer_right: float | None = None,
    inner_right: float | None = None,
) -> ShaftLayer:
    """A circular (tube) layer; conical when the right-end diameters differ from the left.

    >>> from rheolin.mechanics.sections import Material
    >>> steel = Material(2.1e11, 7850.0, nu=0.3)
    >>> circular_layer(steel, 0.05).diameters is None, circular_layer(steel, 0.05, 0, 0.04).section
    (True, None)
    """
    o_r = outer if outer_right is None else outer_right
    i_r = inner if inner_right is None else inner_right
    vals = (float(outer), float(inner), float(o_r), float(i_r))
    if not all(np.isfinite(vals)) or not (0 <= vals[1] < vals[0] and 0 <= vals[3] < vals[2]):
        raise ModelError(
            "shaft diameters: need 0 <= inner < outer at both ends, got outer/inner "
            f"left {vals[0]!r}/{vals[1]!r}, right {vals[2]!r}/{vals[3]!r}"
        )
    if vals[0] == vals[2] and vals[1] == vals[3]:
        nu = float(material.nu)  # type: ignore[arg-type]
        sec = hollow_circular(vals[0], vals[1], nu) if vals[1] > 0 else solid_circular(vals[0], nu)
        return ShaftLayer(material, section=sec)
    return ShaftLayer(material, diameters=vals)


def element_matrices(
    length: float,
    layers: Sequence[ShaftLayer],
    direction: object,
    y_axis: object | None = None,
) -> BeamMatrices:
    """The element's body-frame matrices in global axes: the sum over its layers.

    >>> from rheolin.mechanics.sections import Material
    >>> steel = Material(2.1e11, 7850.0, nu=0.3)
    >>> one = element_matrices(0.1, [circular_layer(steel, 0.05)], [0, 0, 1])
    >>> two = element_matrices(0.1, [circular_layer(steel, 0.05)] * 2, [0, 0, 1])
    >>> bool(np.allclose(two.K, 2 * one.K))
    True
    """
    total: BeamMatrices | None = None
    for layer in layers:
        mat = layer.material
        if layer.diameters is not None:
            b = conical_body_matrices(
                length,
                layer.diameters,
                mat.E,
                float(mat.G),  # type: ignore[arg-type]
                mat.density,
                direction,
                mat.damping_beta,
            )
        else:
            assert layer.section is not None
            b = beam_body_matrices(length, layer.section, mat, direction, y_axis)
        if total is None:
            total = b
            continue
        J = total.node_inertia
        if b.node_inertia is not None:
            J = b.node_inertia if J is None else J + b.node_inertia
        total = BeamMatrices(
            total.M + b.M, total.K + b.K, total.D + b.D, total.gyroscopic + b.gyroscopic, J
        )
    if total is None:
        raise ModelError("a shaft element needs at least one layer")
    return total


# --------------------------------------------------------------------------- model input
def _per_element(x: Any, n: int, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float).ravel()
    if a.size == 1:
        a = np.full(n, a[0])
    if a.size != n or not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ModelError(f"`{name}` must be one value or one per element ({n}), >= 0")
    return a


def shaft_nodes(
    positions: Any, axis: Any, origin: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(z, e, points)``: the axial node coordinates (>= 2, strictly increasing), the unit
    spin axis and the nodes' global positions.

    >>> z, e, p = shaft_nodes([0.0, 0.5], (0, 0, 2), (1.0, 0, 0))
    >>> p.tolist()
    [[1.0, 0.0, 0.0], [1.0, 0.0, 0.5]]
    """
    z = np.asarray(positions, dtype=float).ravel()
    if z.size < 2 or np.any(np.diff(z) <= 0):
        raise ModelError("`positions` must hold >= 2 strictly increasing axial coordinates")
    e = unit_axis(axis, "axis")
    return z, e, np.asarray(origin, float) + np.outer(z, e)


def shaft_materials(
    n: int,
    material: str | None,
    elastic_modulus: Any,
    density: Any,
    poisson_ratio: Any,
    shear_modulus: Any,
    damping_beta: float,
    where: str,
) -> list[Material]:
    """One material per element: the constants given (per shaft or per element), the others
    from the named ``material``; refused when neither (rheolin assumes no material).
    Poisson's ratio is not needed with a shear modulus.

    >>> [m.E for m in shaft_materials(2, "steel", [2e11, 2.1e11], None, None, None, 0.0, "s")]
    [200000000000.0, 210000000000.0]
    """
    need = {"elastic_modulus": elastic_modulus, "density": density}
    if shear_modulus is None:
        need["poisson_ratio"] = poisson_ratio
    c = material_constants(material, need, where)
    nu = c.get("poisson_ratio", poisson_ratio)
    return element_materials(n, c["elastic_modulus"], c["density"], nu, shear_modulus, damping_beta)


def tube_layers(
    materials: Sequence[Material],
    outer: Any,
    inner: Any,
    outer_right: Any = None,
    inner_right: Any = None,
) -> tuple[list[ShaftLayer], dict[str, np.ndarray]]:
    """One circular layer per material (element) and the diameters read: one value or one per
    element, the right ends defaulting to the left ones.

    >>> from rheolin.mechanics.sections import Material
    >>> steel = Material(2.1e11, 7850.0, nu=0.3)
    >>> layers, d = tube_layers([steel, steel], [0.05, 0.04], 0.0, outer_right=0.03)
    >>> d["outer_diameter_right"].tolist(), layers[0].diameters
    ([0.03, 0.03], (0.05, 0.0, 0.03, 0.0))
    """
    n = len(materials)
    do = _per_element(outer, n, "outer_diameter")
    di = _per_element(inner, n, "inner_diameter")
    dor = do if outer_right is None else _per_element(outer_right, n, "outer_diameter_right")
    dir_ = di if inner_right is None else _per_element(inner_right, n, "inner_diameter_right")
    layers = [
        circular_layer(mat, a, b, c, d)
        for mat, a, b, c, d in zip(materials, do, di, dor, dir_, strict=True)
    ]
    diameters = {
        "outer_diameter": do,
        "inner_diameter": di,
        "outer_diameter_right": dor,
        "inner_diameter_right": dir_,
    }
    return layers, diameters


def shaft_layers(
    materials: Sequence[Material],
    section: Section | None,
    outer: Any,
    inner: Any,
    outer_right: Any,
    inner_right: Any,
) -> list[list[ShaftLayer]]:
    """The layers of each element of a new shaft: one ``section`` for every element, or the
    circular (tube) sections of the diameters."""
    if section is not None:
        if not isinstance(section, Section):
            raise ModelError("`section` must be a rheolin.mechanics.sections.Section")
        if outer_right is not None or inner_right is not None:
            raise ModelError("`outer_diameter_right`/`inner_diameter_right` need diameters")
        return [[ShaftLayer(mat, section=section)] for mat in materials]
    if outer is None:
        raise ModelError("give `outer_diameter` (circular shaft) or `section`")
    layers, _ = tube_layers(materials, outer, inner, outer_right, inner_right)
    return [[layer] for layer in layers]


def layer_elements(kind: str, shaft: str, n_el: int, elements: Any) -> list[int]:
    """The element indices a layer covers, on a body of ``kind`` named ``shaft``."""
    if kind != "shaft":
        raise ModelError(f"`shaft`: body {shaft!r} is a {kind} body, not a shaft")
    idx = [int(i) for i in np.atleast_1d(np.asarray(elements)).ravel()]
    if not idx or any(not 0 <= i < n_el for i in idx):
        raise ModelError(f"`elements` must be element indices in [0, {n_el}), got {elements!r}")
    return idx
