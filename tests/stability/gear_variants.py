"""Gearbox variants with unstable speed ranges, for checking range bounds against the
monodromy matrix (tests/stability/test_w30_ranges.py).

The embedded two-stage gearbox (``rheolin example gearbox``) with

* tooth counts 20:70 and 18:72 (as bench/transient.py): ``w1`` = input speed / 14, a common
  period of 14 input revolutions (0.23 s at 3700 rpm) instead of 4757;
* a polymer second stage: its mesh stiffness 1 % of the steel one (single/double tooth
  contact 2.5e6 / 6.5e6 N/m, a 2.6 : 1 variation) and its mesh damping 5 N s/m, so that a
  torsional mode carrying the second mesh (about 990 rad/s) falls to where twice it is the
  mesh frequency ``W_m2 = 72 w1 = 36/7 x input`` at about 3700 rpm;
* light torsional couplings (0.1 N m s/rad at the motor and at the load, not 2 and 20), so
  that this mode is damped by about 6 1/s only.

The result has a **principal** parametric resonance of the second mesh (``2 w_a ~ W_m2``,
``w_a`` about 990 rad/s) between about 3460 and 3900 rpm, and a **combination** resonance
(``w_a + w_b ~ W_m2``, ``w_b`` about 1585 rad/s) near 4800 rpm
(:data:`PRINCIPAL`, :data:`COMBINATION`: the reference bounds).

``coarse=True`` (default) meshes each shaft with 4 nodes (the disks, bearings and couplings;
72 DOFs), which keeps the reference affordable (a monodromy matrix in about 15 s); ``False``
keeps the example's 7 nodes per shaft (126 DOFs: the size of the issue's variant).

Regenerate the reference bounds (tests/stability/data/gear_variant_ranges.json; about an
hour of one core)::

    PYTHONPATH=src python tests/stability/gear_variants.py --regenerate

and the steel variant's (:data:`STEEL`; tests/stability/data/gear_variant_steel.json)::

    PYTHONPATH=src python tests/stability/gear_variants.py --regenerate-steel
"""

from __future__ import annotations

import json
import sys
import time
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

import rheolin as rl

__all__ = [
    "REFERENCE_FILE",
    "STEEL",
    "STEEL_FILE",
    "reference_ranges",
    "steel_reference",
    "variant_document",
    "variant_model",
    "variant_toml",
]

REFERENCE_FILE = Path(__file__).parent / "data" / "gear_variant_ranges.json"

#: The steel variant's stored largest real parts (:func:`steel_reference`).
STEEL_FILE = Path(__file__).parent / "data" / "gear_variant_steel.json"

#: The short-period variant with the example's steel second stage (4.0e8 / 6.5e8 N/m, 2500 N
#: s/m) and couplings (2 and 20 N m s/rad): the gearbox itself but for its tooth counts. At
#: 500 rpm its order-2 confirmation leaves heavily damped exponents open that the lattice
#: grown along their leaks settles (``rheolin.floquet.grown.grown_further``).
STEEL: dict[str, Any] = {
    "stage2_scale": 1.0,
    "stage2_ratio": 6.5 / 4.0,
    "stage2_damping": 2500.0,
    "coupling_damping": (2.0, 20.0),
}

#: Each shaft's node positions and where the example's nodes go on the coarse mesh.
COARSE = {
    "input": ("0 20 50 110 mm", {0: 0, 1: 1, 3: 2, 6: 3}),
    "intermediate": ("20 50 130 160 mm", {0: 0, 1: 1, 5: 2, 6: 3}),
    "output": ("20 130 160 240 mm", {0: 0, 3: 1, 4: 2, 6: 3}),
}


def variant_document(
    *,
    coarse: bool = True,
    stage2_scale: float = 0.01,
    stage2_ratio: float = 2.6,
    stage2_damping: float = 5.0,
    coupling_damping: tuple[float, float] = (0.1, 0.1),
) -> dict[str, Any]:
    """The variant's model file as a dict (see the module docstring): the second stage's
    double-contact stiffness is ``stage2_scale`` times the example's 6.5e8 N/m and
    ``stage2_ratio`` times its single-contact stiffness; ``stage2_damping`` [N s/m];
    ``coupling_damping`` of the motor and load couplings [N m s/rad]."""
    from rheolin.data import example_text

    doc = tomllib.loads(example_text("gearbox"))
    doc["model"]["name"] = "two-stage gearbox, polymer second stage (short period)"
    teeth = {"stage1": (20, 70), "stage2": (18, 72)}
    for mesh in doc["meshes"]:
        mesh["pinion_teeth"], mesh["gear_teeth"] = teeth[mesh["name"]]
        if mesh["name"] == "stage2":
            double = 6.5e8 * stage2_scale
            mesh["double_stiffness"] = f"{double:.6g} N/m"
            mesh["single_stiffness"] = f"{double / stage2_ratio:.6g} N/m"
            mesh["damping"] = f"{stage2_damping:.6g} N*s/m"
    remap: dict[str, dict[int, int]] = {}
    for shaft in doc["shafts"]:
        if coarse:
            positions, nodes = COARSE[shaft["name"]]
            shaft["positions"] = positions
            remap[shaft["name"]] = nodes
            for item in shaft.get("disks", []) + shaft.get("bearings", []):
                item["node"] = nodes[item["node"]]
        for bearing in shaft.get("bearings", []):
            if bearing["name"] == "motor_coupling":
                bearing["damping"] = [f"{coupling_damping[0]:.6g} N*m*s/rad"]
            if bearing["name"] == "load_coupling":
                bearing["damping"] = [f"{coupling_damping[1]:.6g} N*m*s/rad"]
    if coarse:
        for mesh in doc["meshes"]:
            mesh["pinion_node"] = remap[mesh["pinion_body"]][mesh["pinion_node"]]
            mesh["gear_node"] = remap[mesh["gear_body"]][mesh["gear_node"]]
    return doc


def variant_model(**kwargs: Any) -> rl.Model:
    """The variant as a :class:`rheolin.Model` (arguments of :func:`variant_document`)."""
    from rheolin.io import parse_document

    return parse_document(variant_document(**kwargs)).model


def variant_toml(**kwargs: Any) -> str:
    """The variant as model-file text (for the command line)."""
    import tomli_w

    return tomli_w.dumps(variant_document(**kwargs))


def reference_ranges() -> dict[str, Any]:
    """The stored reference bounds (:data:`REFERENCE_FILE`)."""
    return json.loads(REFERENCE_FILE.read_text())


def steel_reference() -> dict[str, Any]:
    """The stored largest real parts of the steel variant (:data:`STEEL_FILE`)."""
    return json.loads(STEEL_FILE.read_text())


#: Speeds [rpm] of the steel variant with a stored largest real part, and the Radau steps
#: per period (the error is the change from half as many).
STEEL_POINTS = (500.0,)
STEEL_STEPS = 32000


def regenerate_steel(path: Path = STEEL_FILE) -> dict[str, Any]:
    """Compute the steel variant's largest real parts from monodromy matrices and write
    them (about 4 minutes of one core)."""
    model = variant_model(**STEEL)
    t0 = time.perf_counter()
    out: dict[str, Any] = {
        "command": "PYTHONPATH=src python tests/stability/gear_variants.py --regenerate-steel",
        "variant": "gear_variants.variant_model(**STEEL) (coarse, 72 DOFs)",
        "points": [],
    }
    return _write_points(model, STEEL_POINTS, STEEL_STEPS, out, path, t0)


def _write_points(
    model: rl.Model,
    speeds: tuple[float, ...],
    steps: int,
    out: dict[str, Any],
    path: Path,
    t0: float,
) -> dict[str, Any]:
    """Add the monodromy matrix's largest real part at each of ``speeds`` [rpm] to
    ``out["points"]`` (``steps`` Radau steps a period), and write ``out`` to ``path``."""
    from monodromy import leading_real

    for rpm in speeds:
        ref = leading_real(model.assemble(rpm * np.pi / 30).system, steps)
        out["points"].append(
            {"rpm": rpm, "max_real": ref.value, "error": ref.error, "steps": ref.steps}
        )
        print(rpm, ref, flush=True)
    out["seconds"] = time.perf_counter() - t0
    path.parent.mkdir(exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")
    return out


#: The unstable ranges of the default variant: per range, the (stable, unstable) speeds
#: [rpm] that bracket each edge.
BRACKETS: dict[str, dict[str, Any]] = {
    "principal": {"lower": (3420.0, 3500.0), "upper": (3880.0, 3800.0)},
    "combination": {"lower": (4400.0, 4480.0), "upper": (5100.0, 5020.0)},
}

#: Radau steps per period of the reference bounds: Brent's method with the first, secant
#: steps with the others (the last change is the stated uncertainty).
STEPS = (2000, 4000, 8000)

#: Speeds [rpm] with a stored largest real part: below, near and inside both ranges.
POINTS = (3000.0, 3420.0, 3700.0, 3880.0, 4480.0, 4800.0, 5020.0)

#: Radau steps per period of the stored largest real parts.
POINT_STEPS = 8000


def regenerate(path: Path = REFERENCE_FILE) -> dict[str, Any]:
    """Compute the reference bounds and values from monodromy matrices and write them."""
    from monodromy import unstable_edge

    model = variant_model()
    t0 = time.perf_counter()
    out: dict[str, Any] = {
        "command": "PYTHONPATH=src python tests/stability/gear_variants.py --regenerate",
        "variant": "gear_variants.variant_model() (coarse, 72 DOFs)",
        "ranges": {},
        "points": [],
    }

    for name, spec in BRACKETS.items():
        found: dict[str, Any] = {"steps": list(STEPS)}
        for side in ("lower", "upper"):
            stable, unstable = spec[side]
            edge, error, count = unstable_edge(model, stable, unstable, steps=STEPS)
            found[f"{side}_rpm"] = edge
            found[f"{side}_uncertainty_rpm"] = error
            found[f"{side}_evaluations"] = count
            print(name, side, edge, error, count, flush=True)
        out["ranges"][name] = found
    return _write_points(model, POINTS, POINT_STEPS, out, path, t0)


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).parent))
    if "--regenerate" in sys.argv[1:]:
        regenerate()
    elif "--regenerate-steel" in sys.argv[1:]:
        regenerate_steel()
    else:
        raise SystemExit(__doc__)
