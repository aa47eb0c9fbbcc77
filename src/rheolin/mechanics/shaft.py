"""Shaft elements made of concentric layers: uniform or conical tubes, each with its material.

An element of a shaft is one or more :class:`ShaftLayer` between the same two nodes (a shaft
with a shrunk-on sleeve, an impeller hub modelled as a mass-only layer, ...). The layers act in
parallel: the element's matrices are the sum of each layer's Timoshenko matrices, every layer
with its own shear parameter (as ROSS does for elements sharing a node).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from .beam import BeamMatrices, beam_body_matrices
from .conical import conical_body_matrices
from .sections import Material, Section, hollow_circular, solid_circular

__all__ = ["ShaftLayer", "circular_layer", "element_matrices"]


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
