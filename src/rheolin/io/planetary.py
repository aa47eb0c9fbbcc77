"""The ``[[planetary]]`` table of the model file: its schema and its ``Model.add_planetary`` call.

One table per set; its keys are ``add_planetary``'s arguments, with the sub-tables
``planet``, ``planet_bearing``, ``sun_mesh`` and ``ring_mesh`` (docs/model-format.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from ..errors import ModelError
from .quantities import (
    Angle,
    DampingNonNeg,
    DensityPos,
    HelixAngle,
    Index,
    LengthNonNeg,
    LengthPos,
    MassPos,
    Name,
    PressureAngle,
    Raw,
    StiffnessNonNeg,
    inertia_matrix,
)
from .units import UnitError, to_si

__all__ = ["Planetary", "planetary_arguments", "planetary_table"]

_COMPONENTS = ("ux", "uy", "uz", "phix", "phiy", "phiz")


class _Table(BaseModel):
    model_config = ConfigDict(extra="forbid")


class _Harmonic(_Table):
    harmonic: int = Field(ge=0, strict=True)
    amplitude: LengthNonNeg
    phase: Angle = 0.0


class SetMesh(_Table):
    """``sun_mesh`` / ``ring_mesh``: the mesh of planet 0 (the others are phased)."""

    stiffness: StiffnessNonNeg | None = None
    contact_ratio: float | None = Field(default=None, ge=1.0, le=2.0)
    single_stiffness: StiffnessNonNeg | None = None
    double_stiffness: StiffnessNonNeg | None = None
    stiffness_harmonics: int = Field(default=10, ge=0, le=500, strict=True)
    damping: DampingNonNeg = 0.0
    transmission_error: list[_Harmonic] = []


class Planet(_Table):
    """``planet``: ``mass`` + ``inertia``, or ``width`` (+ ``outer_diameter``,
    ``inner_diameter``, ``density`` or ``material``)."""

    mass: MassPos | None = None
    inertia: list[Any] | None = None
    outer_diameter: LengthPos | None = None
    width: LengthPos | None = None
    inner_diameter: LengthNonNeg = 0.0
    density: DensityPos | None = None
    material: str | None = None

    @field_validator("inertia")
    @classmethod
    def _inertia(cls, value: list[Any] | None) -> list[Any] | None:
        return inertia_matrix(value, definite=True)


class PlanetBearing(_Table):
    """``planet_bearing``: on the planet's motion relative to its pin, in the planet's radial
    (``ux``), tangential (``uy``) and axial (``uz``) axes."""

    stiffness: Raw
    damping: Raw | None = None
    components: list[Literal["ux", "uy", "uz", "phix", "phiy", "phiz"]] = [
        "ux", "uy", "uz", "phix", "phiy",
    ]  # fmt: skip


class Planetary(_Table):
    """``Model.add_planetary``."""

    name: Name
    sun_body: Name
    sun_node: Index
    ring_body: Name
    ring_node: Index
    carrier_body: Name
    carrier_node: Index
    sun_teeth: int = Field(ge=1, strict=True)
    planet_teeth: int = Field(ge=1, strict=True)
    ring_teeth: int = Field(ge=1, strict=True)
    module: LengthPos
    planets: int | None = Field(default=None, ge=1, strict=True)
    planet_angles: list[Angle] | None = None
    pressure_angle: PressureAngle = float(np.radians(20.0))
    helix_angle: HelixAngle = 0.0
    carrier_radius: LengthPos | None = None
    angle_reference: list[float] | None = None
    side: Literal[1, -1] = 1
    ring_phase: Angle = 0.0
    pin_errors: list[list[Any]] | None = None
    frame: Literal["carrier", "inertial"] = "carrier"
    planet: Planet
    planet_bearing: PlanetBearing
    sun_mesh: SetMesh
    ring_mesh: SetMesh

    @model_validator(mode="after")
    def _spacing(self) -> Planetary:
        if (self.planets is None) == (self.planet_angles is None):
            raise ValueError("give `planets` (equally spaced) or `planet_angles`, one of them")
        return self


def _bearing_matrix(value: Any, comps: Sequence[str], kind: str, path: str) -> np.ndarray:
    """One value per component (or one for all translations), units by component."""
    values = value if isinstance(value, list) else [value] * len(comps)
    if len(values) != len(comps):
        raise ModelError(f"{path}: expected {len(comps)} values (one per component {list(comps)})")
    out = []
    for i, (c, x) in enumerate(zip(comps, values, strict=True)):
        unit = kind if c.startswith("u") else "rotational_" + kind
        try:
            out.append(to_si(x, unit))
        except UnitError as exc:
            raise ModelError(f"{path}[{i}]: {exc}") from None
    return np.asarray(out, dtype=float)


def _mesh(m: SetMesh) -> dict[str, Any]:
    out = m.model_dump(exclude={"transmission_error"})
    te = {
        t.harmonic: (
            t.amplitude * np.cos(t.phase) if t.harmonic == 0
            else t.amplitude / 2 * np.exp(1j * t.phase)
        )
        for t in m.transmission_error
    }  # fmt: skip
    out["transmission_error"] = te or None
    return {k: v for k, v in out.items() if v is not None}


def planetary_arguments(s: Planetary, path: str) -> dict[str, Any]:
    """``add_planetary``'s keyword arguments from a checked table (units converted).

    >>> t = Planetary(name="p", sun_body="s", sun_node=0, ring_body="r", ring_node=0,
    ...     carrier_body="c", carrier_node=0, sun_teeth=20, planet_teeth=20, ring_teeth=60,
    ...     module="3 mm", planets=4, planet={"mass": "1 kg", "inertia": [1e-3, 1e-3, 2e-3]},
    ...     planet_bearing={"stiffness": ["1e8 N/m"] * 3 + ["1e5 N*m/rad"] * 2},
    ...     sun_mesh={"stiffness": "3e8 N/m"}, ring_mesh={"stiffness": "4e8 N/m"})
    >>> a = planetary_arguments(t, "planetary[0]")
    >>> a["module"], float(a["planet_bearing"]["stiffness"][3])
    (0.003, 100000.0)
    """
    kw = s.model_dump(exclude={"planet", "planet_bearing", "sun_mesh", "ring_mesh", "pin_errors"})
    comps = list(s.planet_bearing.components)
    bearing: dict[str, Any] = {"components": comps}
    bearing["stiffness"] = _bearing_matrix(
        s.planet_bearing.stiffness, comps, "stiffness", f"{path}.planet_bearing.stiffness"
    )
    if s.planet_bearing.damping is not None:
        bearing["damping"] = _bearing_matrix(
            s.planet_bearing.damping, comps, "damping", f"{path}.planet_bearing.damping"
        )
    kw["planet_bearing"] = bearing
    kw["planet"] = {k: v for k, v in s.planet.model_dump().items() if v is not None}
    kw["sun_mesh"], kw["ring_mesh"] = _mesh(s.sun_mesh), _mesh(s.ring_mesh)
    if s.pin_errors is not None:
        try:
            kw["pin_errors"] = [[to_si(x, "length") for x in e] for e in s.pin_errors]
        except (UnitError, TypeError) as exc:
            raise ModelError(f"{path}.pin_errors: {exc}") from None
    return {k: v for k, v in kw.items() if v is not None}


def _te_rows(te: Any) -> list[dict[str, Any]]:
    return [
        {"harmonic": 0, "amplitude": abs(float(np.real(e))),
         "phase": 0.0 if np.real(e) >= 0 else float(np.pi)} if int(j) == 0
        else {"harmonic": int(j), "amplitude": 2 * abs(complex(e)),
              "phase": float(np.angle(complex(e)))}
        for j, e in (te or {}).items()
    ]  # fmt: skip


def planetary_table(call: dict[str, Any]) -> dict[str, Any]:
    """The ``[[planetary]]`` table of an ``add_planetary`` call (SI numbers), for
    ``Model.to_toml``; a Fourier series of mesh stiffness has no file form.

    >>> t = planetary_table({"name": "p", "sun_mesh": {"stiffness": 3e8,
    ...     "transmission_error": {1: 1e-6}}, "planet_bearing": {"stiffness": [1.0, 2.0]}})
    >>> t["sun_mesh"]["transmission_error"][0]["amplitude"], t["planet_bearing"]["stiffness"]
    (2e-06, [1.0, 2.0])
    """

    def plain(v: Any) -> Any:
        if isinstance(v, np.ndarray):
            return plain(v.tolist())
        if isinstance(v, list | tuple):
            return [plain(x) for x in v]
        if isinstance(v, np.generic):
            return v.item()
        return v

    out: dict[str, Any] = {}
    for key, value in call.items():
        if value is None:
            continue
        if key in ("sun_mesh", "ring_mesh"):
            mesh = dict(value)
            if isinstance(mesh.get("stiffness"), dict):
                k = mesh["stiffness"]
                if any(v != 0 for j, v in k.items() if j != 0):
                    raise ModelError(
                        f"planetary set {call.get('name')!r}: a Fourier series of `{key}` "
                        "stiffness has no file form"
                    )
                mesh["stiffness"] = float(np.real(k.get(0, 0.0)))
            mesh["transmission_error"] = _te_rows(mesh.get("transmission_error"))
            out[key] = {k: plain(v) for k, v in mesh.items() if v is not None}
        elif key == "planet_bearing":
            b = dict(value)
            comps = list(b.get("components") or _COMPONENTS[:5])
            for name in ("stiffness", "damping"):
                x = b.get(name)
                if x is None:
                    continue
                x = np.asarray(x, dtype=float)
                if x.ndim == 2:  # written on its diagonal: the file form is one value per component
                    idx = [_COMPONENTS.index(c) for c in comps] if x.shape == (6, 6) else None
                    x = np.diag(x)[idx] if idx is not None else np.diag(x)
                b[name] = plain(x)
            b["components"] = comps
            out[key] = b
        else:
            out[key] = plain(dict(value)) if isinstance(value, dict) else plain(value)
    return out
