"""Finely meshed variants of the built-in examples: the same physics on more shaft nodes.

Every element of every shaft is split into equal parts; the original nodes stay nodes, so
disks, bearings, meshes and forces keep their places (their node indices are renumbered).
These models prove the stability method at sizes where the time-averaged modes cannot be
computed densely (docs/stability.md).

>>> import tomllib
>>> spec = tomllib.loads(refined_example("rotor", 401))
>>> shaft = spec["shafts"][0]
>>> len(shaft["positions"].split()) - 1, shaft["disks"][0]["node"], shaft["bearings"][1]["node"]
(401, 200, 400)
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from itertools import pairwise
from typing import Any

import numpy as np
import scipy.sparse as sp
import tomli_w

from ..errors import ModelError
from ..system.periodic import PeriodicSystem
from . import example_text

__all__ = ["gearbox_subdivisions", "mesh_chain", "refine_model", "refined_example"]

#: Per-element shaft fields that may be lists (one value per element): repeated per part.
PER_ELEMENT = (
    "outer_diameter",
    "inner_diameter",
    "elastic_modulus",
    "poisson_ratio",
    "shear_modulus",
    "density",
)


def _positions(text: str) -> tuple[list[float], str]:
    """``"0 20 35 mm"`` -> ``([0, 20, 35], "mm")``."""
    parts = text.split()
    if len(parts) < 3:
        raise ModelError(f"positions: expected numbers and a unit, got {text!r}")
    return [float(p) for p in parts[:-1]], parts[-1]


def _split(values: list[float], parts: list[int]) -> list[float]:
    out = [values[0]]
    for (a, b), m in zip(pairwise(values), parts, strict=True):
        out.extend(a + (b - a) * j / m for j in range(1, m + 1))
    return out


def refine_model(spec: Mapping[str, Any], parts: Mapping[str, int | list[int]]) -> dict[str, Any]:
    """A model specification (parsed TOML) with its shaft elements split.

    Parameters
    ----------
    spec
        The parsed model file (``tomllib.loads``).
    parts
        Per shaft name: the number of parts every element is split into, or one number per
        element. Shafts not named are kept.

    Returns
    -------
    dict
        The refined specification (write it with ``tomli_w.dumps``).
    """
    out: dict[str, Any] = tomllib.loads(tomli_w.dumps(dict(spec)))  # a deep copy
    renumber: dict[str, list[int]] = {}
    for shaft in out.get("shafts", []):
        name = shaft["name"]
        if name not in parts:
            continue
        if "layers" in shaft or any(k.endswith("_right") for k in shaft):
            raise ModelError(f"shafts.{name}: layers and conical elements are not refined")
        values, unit = _positions(shaft["positions"])
        ne = len(values) - 1
        p = parts[name]
        per = [int(p)] * ne if isinstance(p, int) else [int(x) for x in p]
        if len(per) != ne or min(per) < 1:
            raise ModelError(f"parts[{name!r}]: one integer >= 1 per element ({ne})")
        new = _split(values, per)
        shaft["positions"] = " ".join(f"{x:.10g}" for x in new) + f" {unit}"
        starts = [0]
        for m in per:
            starts.append(starts[-1] + m)
        renumber[name] = starts
        for key in PER_ELEMENT:
            if isinstance(shaft.get(key), list):
                shaft[key] = [v for v, m in zip(shaft[key], per, strict=True) for _ in range(m)]
        for item in (*shaft.get("disks", []), *shaft.get("bearings", [])):
            item["node"] = starts[int(item["node"])]
    for shaft in out.get("shafts", []):
        for bearing in shaft.get("bearings", []):
            other = bearing.get("other_body")
            if other in renumber and "other_node" in bearing:
                bearing["other_node"] = renumber[other][int(bearing["other_node"])]
    for mesh in out.get("meshes", []):
        for body, node in (("pinion_body", "pinion_node"), ("gear_body", "gear_node")):
            if mesh[body] in renumber:
                mesh[node] = renumber[mesh[body]][int(mesh[node])]
    for table in ("forces", "torques", "rolling_bearings", "rigid_links"):
        for item in out.get(table, []):
            for body, node in (("body", "node"), ("other_body", "other_node")):
                if item.get(body) in renumber and node in item:
                    item[node] = renumber[item[body]][int(item[node])]
    return out


def gearbox_subdivisions(dof: int) -> int:
    """Parts per element that give the gearbox about ``dof`` DOFs (3 shafts x 6 elements,
    6 DOFs per node): ``3 x (6 m + 1) x 6 ~ dof``."""
    return max(1, round((dof / 18 - 1) / 6))


def refined_example(name: str, nodes: int | None = None, *, dof: int | None = None) -> str:
    """A built-in example with its shafts finely meshed, as model-file text.

    ``rotor``: ``nodes`` shaft nodes (odd, at least 3: the disk stays at midspan).
    ``gearbox``: every element split so that the model has about ``dof`` DOFs (default
    20,000), or into ``nodes`` parts per element.
    """
    spec = tomllib.loads(example_text(name))
    if name == "rotor":
        n = 401 if nodes is None else int(nodes)
        if n < 3 or n % 2 == 0:
            raise ModelError(f"nodes: the rotor needs an odd number >= 3, got {n}")
        parts: dict[str, int | list[int]] = {"rotor": (n - 1) // 2}
        spec["model"]["name"] = f"asymmetric rotor, {n} shaft nodes"
    elif name == "gearbox":
        m = int(nodes) if nodes is not None else gearbox_subdivisions(dof or 20000)
        parts = {s["name"]: m for s in spec["shafts"]}
        total = sum(6 * (6 * m + 1) for _ in spec["shafts"])
        spec["model"]["name"] = f"two-stage gearbox, shafts in {m} parts per element"
        spec["model"]["description"] = f"{spec['model']['description']} ({total:,} DOF)"
    else:
        raise KeyError(f"no refined variant of {name!r}; choose rotor or gearbox")
    refined = refine_model(spec, parts)
    head = f"# rheolin example {name!r}, shafts finely meshed (rheolin.data.fine)\n"
    return head + tomli_w.dumps(refined)


def mesh_chain(
    n: int = 3000,
    *,
    speed: float = 2 * np.pi * 25.0,
    teeth: int = 23,
    mesh_harmonics: int = 5,
    asymmetry: float = 0.1,
    damping_ratio: float = 0.02,
) -> PeriodicSystem:
    """A transmission-like chain of ``n`` DOFs with a gear mesh and an asymmetric body.

    Unit masses and springs of ``1e6 N/m`` stand for a shaft line; a rank-1 mesh stiffness
    ``k_m(t) w w^T`` between DOFs ``n/3`` and ``2n/3`` varies at ``teeth x speed`` as a
    rectangular wave of ``mesh_harmonics`` harmonics; a 2-DOF block on the last two DOFs varies
    at twice the speed (a rotating asymmetry of relative size ``asymmetry``). Damping is
    ``2 zeta`` times the highest frequency's share of the stiffness plus a mass-proportional
    part. The base frequency is the speed [rad/s]; unbalance and transmission-error loads.

    >>> s = mesh_chain(30)
    >>> s.n, max(s.coefficient_harmonics)
    (30, 115)
    """
    if n < 6:
        raise ValueError(f"`n` must be >= 6, got {n}")
    k = 1e6
    main = np.full(n, 2 * k)
    main[-1] = k
    K0 = sp.diags([main, -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, 1, -1], format="csr")
    M0 = sp.identity(n, format="csr")
    D0 = (2 * damping_ratio / (2 * np.sqrt(k))) * K0 + 2 * damping_ratio * 50.0 * M0
    a, b = n // 3, (2 * n) // 3
    w = np.zeros(n)
    w[a], w[b] = 1.0, -1.0
    ww = sp.csr_array(np.outer(w, w))
    k_mesh, duty, depth = 0.5 * k, 0.6, 0.3
    K: dict[int, Any] = {0: sp.csr_array(K0) + k_mesh * ww}
    for j in range(1, mesh_harmonics + 1):
        K[teeth * j] = depth * k_mesh * np.sin(np.pi * j * duty) / (np.pi * j) * ww
    block = sp.lil_array((n, n), dtype=complex)
    block[n - 2 : n, n - 2 : n] = asymmetry * k / 2 * np.array([[1.0, -1j], [-1j, -1.0]])
    K[2] = sp.csr_array(block)
    f1 = np.zeros(n, dtype=complex)
    f1[n - 2 :] = 0.5 * np.array([1.0, -1j])
    f_mesh = np.zeros(n, dtype=complex)
    f_mesh[[a, b]] = [1.0, -1.0]
    return PeriodicSystem(
        speed, M={0: M0}, D={0: D0}, K=K, f={1: f1 * speed**2 * 1e-4, teeth: 10.0 * f_mesh}
    )
