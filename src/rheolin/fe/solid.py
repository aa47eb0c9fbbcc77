"""Linear elastic solids meshed with hexahedra, assembled by scikit-fem (optional dependency).

For examples, tests and benchmarks: a block, a thin plate and a box-shaped gearbox housing
with bearing bores, all as :class:`~rheolin.fe.matrices.FEModel` (translational DOFs, three
per node, node-major). Install with ``pip install rheolin[fe]``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import ModelError
from .matrices import FEModel

__all__ = ["housing_mesh", "solid_model", "tensor_block"]


def _skfem():  # type: ignore[no-untyped-def]
    try:
        import skfem
    except ImportError:  # pragma: no cover - depends on the environment
        raise ModelError(
            "building FE matrices needs scikit-fem: pip install 'rheolin[fe]'"
        ) from None
    return skfem


def tensor_block(
    size: Sequence[float], cells: Sequence[int], origin: Sequence[float] = (0.0, 0.0, 0.0)
) -> tuple[np.ndarray, np.ndarray]:
    """Points ``(n, 3)`` and hexahedra ``(m, 8)`` of a box split into ``cells`` per axis.

    >>> p, t = tensor_block((1.0, 1.0, 1.0), (2, 1, 1))
    >>> p.shape, t.shape
    ((12, 3), (2, 8))
    """
    sk = _skfem()
    axes = [
        o + np.linspace(0.0, s, int(c) + 1) for o, s, c in zip(origin, size, cells, strict=True)
    ]
    mesh = sk.MeshHex.init_tensor(*axes)
    return np.asarray(mesh.p.T, dtype=float), np.asarray(mesh.t.T, dtype=np.int64)


def solid_model(
    points: np.ndarray,
    hexes: np.ndarray,
    elastic_modulus: float = 2.1e11,
    poisson_ratio: float = 0.3,
    density: float = 7850.0,
) -> FEModel:
    """Stiffness and consistent mass of trilinear hexahedra (scikit-fem), 3 DOFs per node.

    Unused points are dropped. DOF ``3 i + c`` is component ``c`` of node ``i``.

    >>> p, t = tensor_block((0.1, 0.1, 0.1), (1, 1, 1))
    >>> fe = solid_model(p, t)
    >>> fe.n_dof, round(float(fe.M.sum()) / 3, 6)   # total mass 7.85 kg, three directions
    (24, 7.85)
    """
    sk = _skfem()
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    used = np.unique(hexes)
    renum = np.full(points.shape[0], -1, dtype=np.int64)
    renum[used] = np.arange(used.size)
    mesh = sk.MeshHex(np.ascontiguousarray(points[used].T), np.ascontiguousarray(renum[hexes].T))
    basis = sk.Basis(mesh, sk.ElementVector(sk.ElementHex1()))
    lam, mu = lame_parameters(elastic_modulus, poisson_ratio)
    K = sk.asm(linear_elasticity(lam, mu), basis)

    @sk.BilinearForm
    def mass(u, v, w):  # type: ignore[no-untyped-def]
        return density * sk.helpers.dot(u, v)

    M = sk.asm(mass, basis)
    order = np.asarray(basis.nodal_dofs.T, dtype=np.int64).ravel()  # node-major
    if not np.array_equal(order, np.arange(order.size)):
        K, M = K[order][:, order], M[order][:, order]
    return FEModel.solid(K, M, mesh.p.T)


def housing_mesh(
    size: Sequence[float],
    wall: float,
    element: float,
    bores: Sequence[tuple[float, float, float]] = (),
) -> tuple[np.ndarray, np.ndarray]:
    """A closed box housing (outer ``size``, wall thickness ``wall``) of hexahedra about
    ``element`` long, with circular bores ``(x, y, radius)`` through the two walls normal to
    z (the shaft axes run along z).

    >>> p, t = housing_mesh((0.3, 0.2, 0.1), 0.02, 0.02, [(0.1, 0.1, 0.02)])
    >>> t.shape[1], bool(len(t) < 15 * 10 * 5)
    (8, True)
    """
    sx, sy, sz = (float(x) for x in size)
    cells = [max(2, round(s / element)) for s in (sx, sy, sz)]
    points, hexes = tensor_block((sx, sy, sz), cells)
    centres = points[hexes].mean(axis=1)
    inner = np.all((centres > wall) & (centres < np.array([sx, sy, sz]) - wall), axis=1)  # cavity
    keep = ~inner
    for x, y, r in bores:
        keep &= np.hypot(centres[:, 0] - x, centres[:, 1] - y) > r
    if not keep.any():
        raise ModelError("`wall`/`element`: the housing has no elements left")
    return points, hexes[keep]
