"""Import rotors saved by ROSS (``ross.Rotor.save``, ``.toml`` or ``.json``) without ROSS.

ROSS saves every element with the arguments that rebuild it (``ShaftElement_<tag>``,
``DiskElement_<tag>``, ``BearingElement_<tag>``, ``SealElement_<tag>``, ``PointMass_<tag>``;
the file also holds ``ross_version`` and ``[parameters]``). The import maps them one to one:

* shaft elements -> one rheolin shaft ``"rotor"`` along ``z``; node ``n`` at the sum of the
  preceding element lengths. Elements sharing a node number are layers in parallel
  (:meth:`~rheolin.mechanics.Model.add_shaft_layer`, e.g. sleeves and mass-only hubs); tapered
  elements (``idl != idr`` or ``odl != odr``) become conical elements with ROSS's matrices
  (:mod:`rheolin.mechanics.conical`). Each element keeps its material (``E``, ``G_s``, ``rho``).
* disks -> :meth:`~rheolin.mechanics.Model.add_disk` with mass ``m`` and inertia
  ``(Id, Id, Ip)``.
* bearings and seals -> :meth:`~rheolin.mechanics.Model.add_bearing` on ``ux, uy, uz`` with
  ``k``, ``c``, ``m`` (2x2 cross-coupled plus axial); a ``frequency`` table becomes a speed
  table interpolated as ROSS does (``interpolation="smoothing"``, extrapolated).
* point masses -> non-rotating rigid bodies ``"point_mass_<n>"`` at the linked node's position
  (``mx``, ``my`` and ``mz`` must be equal, ROSS's usual ``m``); their rotations, which no ROSS
  element touches, get a unit rotary inertia on a unit-stiffness ground spring (decoupled
  modes at 1 rad/s, reported by :func:`decoupled_dofs`), bearings with ``n_link`` attach to them.

Features rheolin does not reproduce exactly are refused with the element's name: axial force
and torque prestress, stationary proportional damping (``alpha``, ``beta``), shear or rotary
inertia switched off, the Hutchinson shear factor, and other element classes (magnetic, ball or
roller bearings must be saved as plain tables first).
"""

from __future__ import annotations

import json
import tempfile
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ModelError
from ..mechanics.model import Model

__all__ = ["model_from_ross", "read_ross_document"]

_SHAFT_OK = dict(
    axial_force=0,
    torque=0,
    alpha=0,
    beta=0,
    shear_effects=True,
    rotary_inertia=True,
    gyroscopic=True,
    shear_method_calc="cowper",
)
_COEFFS = ("k", "c", "m")


def model_from_ross(source: Any) -> Model:
    """A :class:`~rheolin.mechanics.Model` from a ROSS rotor: a ``ross.Rotor``, the path of
    a file it saved, or that file already read into a dict.

    Examples
    --------
    >>> doc = {"ross_version": "2.3.0", "parameters": {},
    ...        "ShaftElement_0": {"L": 0.5, "idl": 0.0, "odl": 0.05, "n": 0,
    ...                           "material": {"rho": 7810.0, "E": 211e9, "G_s": 81.2e9}},
    ...        "BearingElement_0": {"n": 0, "kxx": [1e6], "cxx": [0.0]},
    ...        "BearingElement_1": {"n": 1, "kxx": [1e6], "cxx": [0.0]}}
    >>> m = model_from_ross(doc)
    >>> sorted(m.bodies), sorted(m.joints)
    (['rotor'], ['BearingElement_0', 'BearingElement_1'])
    """
    if isinstance(source, dict):
        return read_ross_document(source)
    if isinstance(source, str | Path):
        return read_ross_document(_read(Path(source)))
    if hasattr(source, "save") and hasattr(source, "shaft_elements"):
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "rotor.toml"
            source.save(path)
            return read_ross_document(_read(path))
    raise ModelError(
        f"`rotor`: expected a ross.Rotor, a ROSS rotor file path or its dict, got "
        f"{type(source).__name__}"
    )


def _read(path: Path) -> dict[str, Any]:
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ModelError(f"cannot read ROSS file {str(path)!r}: {exc.strerror}") from None
    try:
        if path.suffix.lower() == ".json":
            return dict(json.loads(raw.decode("utf-8")))
        return tomllib.loads(raw.decode("utf-8"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise ModelError(f"{path}: not a ROSS rotor file: {exc}") from None


def _kind(key: str) -> str:
    return key.split("_", 1)[0]


def _num(v: Any, name: str, key: str, default: Any = None) -> float:
    """``v[name]`` as a finite float (ROSS saves SI numbers), else a ModelError naming
    ``key.name``; ``default`` when the field is missing (None: required)."""
    x = v.get(name) if isinstance(v, dict) else None
    if x is None:
        if default is None:
            raise ModelError(f"{key}.{name}: required (a number in SI units)")
        x = default
    if isinstance(x, bool) or not isinstance(x, int | float):
        raise ModelError(
            f"{key}.{name}: expected a number in SI units (ROSS saves plain numbers), got {x!r}"
        )
    if not np.isfinite(x):
        raise ModelError(f"{key}.{name}: must be finite, got {x!r}")
    return float(x)


def _numbers(x: Any, where: str) -> np.ndarray:
    """A number or a list of numbers as a 1-D float array, else a ModelError at ``where``."""
    values = x if isinstance(x, list) else [x]
    if not values or any(
        isinstance(e, bool) or not isinstance(e, int | float) or not np.isfinite(e) for e in values
    ):
        raise ModelError(f"{where}: expected finite numbers in SI units, got {x!r}")
    return np.asarray(values, dtype=float)


def read_ross_document(doc: dict[str, Any]) -> Model:
    """A :class:`~rheolin.mechanics.Model` from a ROSS rotor file read into a dict."""
    items = {
        k: v
        for k, v in doc.items()
        if k not in ("parameters", "ross_version") and not k.startswith("_")
    }
    known = ("ShaftElement", "DiskElement", "BearingElement", "SealElement", "PointMass")
    other = sorted({_kind(k) for k in items} - set(known))
    if other:
        raise ModelError(
            f"ROSS file: element classes {other} are not supported; supported: {list(known)} "
            "(save magnetic, ball or roller bearings as BearingElement coefficient tables)"
        )
    for key, v in items.items():
        if not isinstance(v, dict):
            raise ModelError(f"{key}: expected a table of the element's arguments")
    shafts = [(k, v) for k, v in items.items() if _kind(k) == "ShaftElement"]
    if not shafts:
        raise ModelError("ROSS file: no ShaftElement; the rotor needs a shaft")
    model = Model()
    positions = _add_shaft(model, shafts)
    for key, v in items.items():
        if _kind(key) == "DiskElement":
            n = _int(v, "n", key)
            _check_node(n, len(positions), key)
            Id, Ip = _num(v, "Id", key), _num(v, "Ip", key)
            _at(key, model.add_disk, "rotor", n, mass=_num(v, "m", key),
                inertia=np.diag([Id, Id, Ip]))  # fmt: skip
    masses = {}
    for key, v in items.items():
        if _kind(key) == "PointMass":
            n = _int(v, "n", key)
            masses[n] = (key, v)
    links = {}
    for key, v in items.items():
        if _kind(key) in ("BearingElement", "SealElement") and v.get("n_link") is not None:
            links[_int(v, "n_link", key)] = _int(v, "n", key)
    point_nodes: dict[int, str] = {}
    for n, (key, v) in sorted(masses.items()):
        point_nodes[n] = _add_point_mass(model, key, v, n, links, positions, point_nodes)
    for key, v in items.items():
        if _kind(key) in ("BearingElement", "SealElement"):
            _add_bearing(model, key, v, len(positions), point_nodes)
    return model


def _at(key: str, fn: Any, *args: Any, **kw: Any) -> Any:
    """``fn(*args, **kw)`` with a model error prefixed by the element's name."""
    try:
        return fn(*args, **kw)
    except ModelError as exc:
        raise ModelError(f"{key}: {exc}") from None


def _int(v: dict[str, Any], name: str, key: str) -> int:
    x = v.get(name)
    if isinstance(x, bool) or not isinstance(x, int) or x < 0:
        raise ModelError(f"{key}.{name}: must be a node number >= 0, got {x!r}")
    return x


def _check_node(n: int, n_nodes: int, key: str) -> None:
    if n >= n_nodes:
        raise ModelError(f"{key}.n: node {n} is not a shaft node (0..{n_nodes - 1})")


def _add_shaft(model: Model, shafts: list[tuple[str, dict[str, Any]]]) -> np.ndarray:
    groups: dict[int, list[tuple[str, dict[str, Any]]]] = {}
    for key, v in shafts:
        for name, ok in _SHAFT_OK.items():
            if v.get(name, ok) != ok:
                raise ModelError(
                    f"{key}.{name}: {v[name]!r} is not supported by the import (needs {ok!r})"
                )
        if not isinstance(v.get("material"), dict):
            raise ModelError(f"{key}.material: the material table (rho, E, G_s) is missing")
        groups.setdefault(_int(v, "n", key), []).append((key, v))
    nodes = sorted(groups)
    if nodes != list(range(len(nodes))):
        raise ModelError(f"ShaftElement.n: element numbers must be 0..N-1, got {nodes}")
    lengths = []
    for key, v in shafts:
        mat = v["material"]
        for name in ("E", "G_s", "rho"):
            _num(mat, name, f"{key}.material")
        for name in ("L", "odl"):
            _num(v, name, key)
        for name in ("idl", "odr", "idr"):
            if v.get(name) is not None:
                _num(v, name, key)
    for n in nodes:
        Ls = {float(v["L"]) for _, v in groups[n]}
        if len(Ls) != 1:
            raise ModelError(f"ShaftElement n={n}: elements sharing a node differ in length {Ls}")
        lengths.append(Ls.pop())
    z = np.concatenate([[0.0], np.cumsum(lengths)])
    first = [groups[n][0][1] for n in nodes]

    def col(name: str, vs: list[dict[str, Any]], default: str | None = None) -> list[float]:
        return [
            float(v[name] if v.get(name) is not None else v.get(default or name) or 0.0) for v in vs
        ]

    _at(
        "ShaftElement",
        model.add_shaft,
        "rotor",
        z.tolist(),
        outer_diameter=col("odl", first),
        inner_diameter=col("idl", first),
        outer_diameter_right=col("odr", first, "odl"),
        inner_diameter_right=col("idr", first, "idl"),
        elastic_modulus=[v["material"]["E"] for v in first],
        shear_modulus=[v["material"]["G_s"] for v in first],
        density=[v["material"]["rho"] for v in first],
    )
    for n in nodes:
        for _, v in groups[n][1:]:
            mat = v["material"]
            idl = float(v.get("idl") or 0.0)
            _at(
                key,
                model.add_shaft_layer,
                "rotor",
                [n],
                float(v["odl"]),
                idl,
                elastic_modulus=mat["E"],
                shear_modulus=mat["G_s"],
                density=mat["rho"],
                outer_diameter_right=float(v["odl"] if v.get("odr") is None else v["odr"]),
                inner_diameter_right=float(
                    v.get("idl") or 0.0 if v.get("idr") is None else v["idr"]
                ),
            )
    return z


def _add_point_mass(
    model: Model,
    key: str,
    v: dict[str, Any],
    n: int,
    links: dict[int, int],
    z: np.ndarray,
    placed: dict[int, str],
) -> str:
    m = [v.get(c) for c in ("mx", "my", "mz")]
    if all(x is None for x in m):
        m = [v.get("m")] * 3
    vals = [_num(v, c, key) for c, x in zip(("mx", "my", "mz"), m, strict=True) if x is not None]
    if all(v.get(c) is None for c in ("mx", "my", "mz")) and v.get("m") is not None:
        vals = [_num(v, "m", key)] * 3
    if len(vals) != 3 or len(set(vals)) != 1 or vals[0] <= 0:
        raise ModelError(f"{key}: point masses need mx = my = mz > 0, got {m}")
    # position: that of the shaft node it hangs from (through the chain of links)
    at, seen = n, set()
    while at not in range(len(z)) and at in links and at not in seen:
        seen.add(at)
        at = links[at]
    pos = (0.0, 0.0, float(z[at])) if at < len(z) else (0.0, 0.0, 0.0)
    name = f"point_mass_{n}"
    model.add_rigid_body(name, pos, vals[0], (1.0, 1.0, 1.0), speed_ratio=0)
    model.add_bearing(
        f"{name}_rotations", name, 0, [1.0, 1.0, 1.0], 0.0, components=("phix", "phiy", "phiz")
    )
    return name


def _coefficient(v: dict[str, Any], name: str, n: int, key: str) -> np.ndarray:
    x = v.get(name)
    if x is None:
        diag = {"kyy": "kxx", "cyy": "cxx", "myy": "mxx"}
        x = v.get(diag[name], 0.0) if name in diag else 0.0
    a = _numbers(x, f"{key}.{name}").ravel()
    if a.size == 1:
        a = np.full(n, a[0])
    if a.size != n or not np.all(np.isfinite(a)):
        raise ModelError(f"{key}.{name}: expected {n} finite values (one per frequency)")
    return a


def _add_bearing(
    model: Model, key: str, v: dict[str, Any], n_nodes: int, points: dict[int, str]
) -> None:
    n = _int(v, "n", key)
    freq = v.get("frequency")
    speeds = None if freq is None else _numbers(freq, f"{key}.frequency").ravel()
    ns = 1 if speeds is None else speeds.size
    tabs = []
    for c in _COEFFS:
        xx, xy, yx, yy, zz = (
            _coefficient(v, f"{c}{s}", ns, key) for s in ("xx", "xy", "yx", "yy", "zz")
        )
        tabs.append(
            np.array(
                [
                    [[a, b, 0.0], [d, e, 0.0], [0.0, 0.0, f]]
                    for a, b, d, e, f in zip(xx, xy, yx, yy, zz, strict=True)
                ]
            )
        )
    body, node = ("rotor", n) if n < n_nodes else (points.get(n), 0)
    if body is None:
        raise ModelError(f"{key}.n: node {n} is neither a shaft node nor a point mass")
    other_body: str | None = None
    other_node: int | None = None
    link = v.get("n_link")
    if link is not None:
        link = _int(v, "n_link", key)
        other_body, other_node = ("rotor", link) if link < n_nodes else (points.get(link), 0)
        if other_body is None:
            raise ModelError(f"{key}.n_link: node {link} is neither a shaft node nor a point mass")
    comps = ("ux", "uy", "uz")
    if speeds is None or speeds.size == 1:
        _at(key, model.add_bearing, key, body, node, tabs[0][0], tabs[1][0], comps, other_body,
            other_node, mass=tabs[2][0])  # fmt: skip
        return
    order = np.argsort(speeds)
    _at(
        key,
        model.add_bearing,
        key,
        body,
        node,
        tabs[0][order],
        tabs[1][order],
        comps,
        other_body,
        other_node,
        mass=tabs[2][order],
        speeds=speeds[order].tolist(),
        interpolation="smoothing",
        extrapolate=True,
    )
