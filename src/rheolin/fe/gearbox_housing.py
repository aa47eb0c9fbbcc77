"""The embedded gearbox in a flexible housing: an example built on the fly (scikit-fem).

A closed steel box of hexahedra around the gearbox (walls 20 mm thick, shafts along z), with
bores for the six rolling bearings and its feet (the bottom face) clamped. Each bearing seat,
the bore's surface in its wall, is tied to a rheolin node by an averaging (RBE3-like)
coupling; the B-side seats of the input and intermediate shafts sit in the far wall, so their
couplings carry a lever arm (a box has no intermediate walls). The housing is condensed
(Craig-Bampton) and the gearbox file's six bearings are rewired from ground to its nodes
(``other_body``): ``rheolin example gearbox-housing --out DIR`` writes both files.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from ..data import example_text
from ..errors import ModelError
from .coupling import Coupling

__all__ = ["BEARINGS", "build", "housing", "seat_couplings"]

#: The housing box in the gearbox's axes [m]: origin and size (shafts along z, at y = 0).
ORIGIN = np.array([-0.070, -0.090, 0.010])
SIZE = (0.365, 0.200, 0.200)
WALL = 0.020
#: Bearings: name, shaft axis (x, y), outer radius of the bearing (the bore), z, wall.
BEARINGS = [
    ("input_A", (0.000, 0.0), 0.031, 0.020, "A"),
    ("input_B", (0.000, 0.0), 0.031, 0.110, "B"),
    ("intermediate_A", (0.090, 0.0), 0.040, 0.020, "A"),
    ("intermediate_B", (0.090, 0.0), 0.040, 0.160, "B"),
    ("output_A", (0.225, 0.0), 0.050, 0.020, "A"),
    ("output_B", (0.225, 0.0), 0.050, 0.200, "B"),
]


def housing(element: float, elastic_modulus: float = 2.1e11) -> Any:
    """The housing's :class:`~rheolin.fe.FEModel` (steel: density 7850 kg/m^3, nu 0.3)."""
    try:
        from .solid import housing_mesh, solid_model
    except ImportError:  # pragma: no cover - the fe extra
        raise ModelError("this example needs scikit-fem: pip install 'rheolin[fe]'") from None
    bores = sorted({(xy, r) for _, xy, r, _, _ in BEARINGS})
    local = [(x - ORIGIN[0], y - ORIGIN[1], r) for (x, y), r in bores]
    points, hexes = housing_mesh(SIZE, WALL, element, local)
    return solid_model(
        points + ORIGIN, hexes, elastic_modulus=elastic_modulus, poisson_ratio=0.3, density=7850.0
    )


def seat_couplings(fe: Any, element: float) -> list[Coupling]:
    """One averaging coupling per bearing: the nodes on its bore surface in its wall (each
    node to the bore it is closest to)."""
    x = fe.coordinates
    walls = {
        "A": (ORIGIN[2], ORIGIN[2] + WALL),
        "B": (ORIGIN[2] + SIZE[2] - WALL, ORIGIN[2] + SIZE[2]),
    }
    bores = sorted({(xy, r) for _, xy, r, _, _ in BEARINGS})
    gaps = np.column_stack(
        [np.abs(np.hypot(x[:, 0] - bx, x[:, 1] - by) - r) for (bx, by), r in bores]
    )
    nearest = np.argmin(gaps, axis=1)
    out = []
    for name, (bx, by), r, z, wall in BEARINGS:
        lo, hi = walls[wall]
        k = bores.index(((bx, by), r))
        ring = (gaps[:, k] < element) & (nearest == k)
        nodes = np.flatnonzero(ring & (x[:, 2] >= lo - 1e-9) & (x[:, 2] <= hi + 1e-9))
        if nodes.size < 3:
            raise ModelError(f"element: the seat of {name} has {nodes.size} nodes; use smaller")
        out.append(Coupling(name, nodes, [bx, by, z], kind="average"))
    return out


def rewired(npz_name: str, positions: np.ndarray) -> str:
    """The gearbox file with its six bearings on the housing's nodes, and the housing."""
    text = example_text("gearbox")
    for k, (name, *_rest) in enumerate(BEARINGS):
        text, n = re.subn(
            rf'^(name = "{name}".*)$',
            rf'\1\nother_body = "housing"\nother_node = {k}',
            text,
            flags=re.M,
        )
        if n != 1:  # pragma: no cover - the example file changed
            raise ModelError(f"the gearbox example has no bearing {name!r}")
    pos = ", ".join(f'"{a:.9g} {b:.9g} {c:.9g} m"' for a, b, c in positions)
    return (
        text.replace('name = "two-stage gearbox"', 'name = "two-stage gearbox in a housing"', 1)
        + "\n# The housing: a Craig-Bampton body written by `rheolin example gearbox-housing`\n"
        + f'[[condensed_bodies]]\nname = "housing"\npath = "{npz_name}"\n'
        + f"positions = [{pos}]   # the six bearing seats\nspeed_ratio = 0\n"
    )


def build(
    directory: str | Path,
    element: float = 0.012,
    *,
    elastic_modulus: float = 2.1e11,
    cutoff_hz: float = 3000.0,
    modes: int = 10,
) -> Path:
    """Write ``housing.npz`` and ``gearbox_in_housing.toml`` into ``directory`` (atomically);
    return the model file's path."""
    from .craig_bampton import condense

    d = Path(directory)
    fe = housing(element, elastic_modulus)
    d.mkdir(parents=True, exist_ok=True)
    feet = fe.dofs_of(fe.nodes_where(lambda x: x[:, 1] < ORIGIN[1] + 1e-9))
    body = condense(
        fe, None, seat_couplings(fe, element), modes=modes, fixed=feet, cutoff_hz=cutoff_hz
    )
    body.save(d / "housing.npz")
    from ..io.atomic import atomic_write

    path = d / "gearbox_in_housing.toml"
    with atomic_write(path) as tmp:
        tmp.write_text(rewired("housing.npz", body.positions))
    return path
