"""The model file schema (TOML), checked by pydantic: one table class per kind of item.

Field names are those of :class:`rheolin.mechanics.Model`'s methods. Structure and units are
checked here (the unit-checked field types are in :mod:`rheolin.io.quantities`); references
between items (bodies, nodes, gear geometry) in :mod:`rheolin.io.build`. See
``docs/model-format.md``.
"""

from __future__ import annotations

import typing
from collections.abc import Sequence
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from ..mechanics.rolling import MAX_ELEMENTS
from ..mechanics.sections import MATERIALS
from .planetary import Planetary
from .quantities import (
    Angle,
    AreaPos,
    CoupleUnbalanceNonNeg,
    DampingNonNeg,
    DensityNonNeg,
    DensityPos,
    DiskBore,
    DiskSize,
    ForcePos,
    HelixAngle,
    Index,
    Length,
    LengthNonNeg,
    LengthPos,
    MassNonNeg,
    MassPos,
    Name,
    PressureAngle,
    PressurePos,
    Ratio,
    Raw,
    SecondMomentPos,
    ShaftBore,
    ShaftDiameter,
    SpeedPos,
    StiffnessNonNeg,
    TimeNonNeg,
    UnbalanceNonNeg,
    VecAcceleration,
    VecDensityNonNeg,
    VecDimensionless,
    VecForce,
    VecForceNonNeg,
    VecLength,
    VecLengthNonNeg,
    VecLengthPos,
    VecMoment,
    VecPressurePos,
    VecSpeedNonNeg,
    VecStiffnessPos,
    ViscosityPos,
    hertz_stiffness,
    inertia_matrix,
)
from .units import to_si

__all__ = [
    "Bearing",
    "Disk",
    "Force",
    "Mesh",
    "ModelFile",
    "RigidBody",
    "RollingBearing",
    "Shaft",
    "Torque",
    "field_path",
    "table_class",
]

#: Harmonics of a rectangular-wave mesh stiffness beyond this are refused: the 500th of a
#: contact-ratio wave is below 1e-3 of the first, and each adds two generators to the
#: harmonic set (its size, and the memory, grow with their number).
MAX_STIFFNESS_HARMONICS = 500


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Section(_Strict):
    """General section (``rheolin.mechanics.sections.general_section``)."""

    area: AreaPos
    Iy: SecondMomentPos
    Iz: SecondMomentPos
    torsion_constant: SecondMomentPos
    kappa_y: float = Field(default=float("inf"), ge=1e-3)  # shear coefficient (inf: no shear)
    kappa_z: float = Field(default=float("inf"), ge=1e-3)


class Disk(_Strict):
    """``Model.add_disk`` (the body is the enclosing shaft or rigid body)."""

    node: Index
    mass: MassNonNeg | None = None
    inertia: list[Any] | None = None
    outer_diameter: DiskSize | None = None
    width: DiskSize | None = None
    density: DensityPos | None = None
    material: Material | None = None
    inner_diameter: DiskBore = 0.0
    unbalance: UnbalanceNonNeg = 0.0
    unbalance_angle: Angle = 0.0
    couple_unbalance: CoupleUnbalanceNonNeg = 0.0
    couple_angle: Angle = 0.0
    axial_offset: Length = 0.0
    balance_grade: str | None = None
    balance_speed: SpeedPos | None = None
    balance_mass: MassPos | None = None

    @model_validator(mode="after")
    def _balance(self) -> Disk:
        if self.balance_grade is None:
            if self.balance_speed is not None or self.balance_mass is not None:
                raise ValueError("balance_speed and balance_mass need balance_grade")
            return self
        if self.unbalance:
            raise ValueError(
                "give either unbalance or balance_grade (the permissible residual unbalance "
                "of ISO 21940-11), not both"
            )
        if self.balance_speed is None:
            raise ValueError(
                "balance_grade needs balance_speed, the rotor's maximum service speed "
                "(e.g. '6000 rpm')"
            )
        return self

    @field_validator("inertia")
    @classmethod
    def _inertia(cls, value: list[Any] | None) -> list[Any] | None:
        return inertia_matrix(value, definite=False)


Material = Literal["steel", "stainless_steel", "cast_iron", "aluminium", "titanium"]


def material_constant(table: Any, key: str) -> float | None:
    """``table.key``, else the value of its named ``material`` (None when neither)."""
    value = getattr(table, key)
    if value is None and getattr(table, "material", None) is not None:
        return MATERIALS[table.material][key]
    return None if value is None else float(value)


Components = Literal["all"] | list[Literal["ux", "uy", "uz", "phix", "phiy", "phiz"]]


class Journal(_Strict):
    """A plain journal bearing by the short-bearing theory (rheolin.mechanics.journal)."""

    diameter: LengthPos
    length: LengthPos
    clearance: LengthPos
    viscosity: ViscosityPos
    load: ForcePos
    load_direction: list[float] = [0.0, -1.0, 0.0]


class Bearing(_Strict):
    """``Model.add_bearing`` (the body is the enclosing shaft or rigid body).

    With ``speeds`` (of the bearing's body), ``stiffness``, ``damping`` and ``mass`` are
    lists with one entry per speed (or one value for every speed)."""

    name: Name
    node: Index
    stiffness: Raw = 0.0
    damping: Raw = 0.0
    mass: Raw = 0.0
    components: Components = ["ux", "uy"]
    other_body: Name | None = None
    other_node: Index | None = None
    frame: Name | None = None
    speeds: VecSpeedNonNeg | None = None
    interpolation: Literal["cubic", "linear", "pchip", "akima", "smoothing"] = "cubic"
    extrapolate: bool = False
    offset: VecLength | None = None
    other_offset: VecLength | None = None
    preload: list[Any] | None = None
    journal: Journal | None = None

    @model_validator(mode="after")
    def _journal(self) -> Bearing:
        if self.journal is None:
            return self
        if self.speeds is None:
            raise ValueError(
                "a journal bearing needs `speeds` (of its shaft), where its coefficients are "
                "computed and between which they are interpolated"
            )
        if np.any(np.asarray(self.stiffness, dtype=object) != 0) or np.any(
            np.asarray(self.damping, dtype=object) != 0
        ):
            raise ValueError("give either `journal` or `stiffness`/`damping`, not both")
        if self.other_body is not None or self.frame is not None:
            raise ValueError("a journal bearing goes from its shaft to ground (no other_body)")
        return self


class RollingBearing(_Strict):
    """``Model.add_rolling_bearing``: a load-dependent rolling-element bearing."""

    name: Name
    node: Index
    law: Literal["elements", "radial", "table"] = "elements"
    kind: Literal["ball", "roller"] = "ball"
    stiffness: Raw | None = None
    elements: int = Field(default=0, ge=0, le=MAX_ELEMENTS, strict=True)
    clearance: LengthNonNeg = 0.0
    angle: Angle = 0.0
    deflection: VecLengthNonNeg | None = None
    force: VecForceNonNeg | None = None
    damping: DampingNonNeg = 0.0
    other_body: Name | None = None
    other_node: Index | None = None

    @model_validator(mode="after")
    def _law(self) -> RollingBearing:
        from ..mechanics.rolling import EXPONENTS

        if self.law == "table":
            if self.deflection is None or self.force is None:
                raise ValueError("law = 'table' needs `deflection` and `force` (equally many)")
            if self.stiffness is not None:
                raise ValueError("law = 'table': give `deflection` and `force`, not `stiffness`")
            return self
        if self.stiffness is None:
            raise ValueError(
                f"law = {self.law!r} needs `stiffness` (N/m^n of the Hertz law, n = 3/2 for "
                "ball, 10/9 for roller contact)"
            )
        if self.law == "elements" and self.elements < 3:
            raise ValueError(
                "law = 'elements' needs `elements` (the number of balls/rollers, >= 3)"
            )
        try:
            self.stiffness = hertz_stiffness(self.stiffness, EXPONENTS[self.kind])
        except ValueError as exc:
            raise ValueError(f"`stiffness`: {exc}") from None
        return self


class Torque(_Strict):
    """``Model.add_torque``: a static torque about the body's axis, or ``"reaction"``."""

    name: Name
    body: Name
    node: Index
    torque: Any = "reaction"

    @field_validator("torque")
    @classmethod
    def _torque(cls, value: Any) -> Any:
        if value == "reaction":
            return value
        return to_si(value, "moment")


class ShaftLayer(_Strict):
    """``Model.add_shaft_layer``: a concentric layer (sleeve, hub) over some elements."""

    elements: list[Index]
    outer_diameter: VecLengthPos
    inner_diameter: VecLengthNonNeg = [0.0]
    outer_diameter_right: VecLengthPos | None = None
    inner_diameter_right: VecLengthNonNeg | None = None
    elastic_modulus: PressurePos = 2.1e11
    poisson_ratio: float | None = Field(default=None, gt=-1.0, lt=0.5)
    shear_modulus: PressurePos | None = None
    density: DensityNonNeg = 7850.0


class _Body(_Strict):
    name: Name
    axis: VecDimensionless = [0.0, 0.0, 1.0]
    speed_ratio: Ratio | None = None
    disks: list[Disk] = []
    bearings: list[Bearing] = []
    rolling_bearings: list[RollingBearing] = []

    @field_validator("axis")
    @classmethod
    def _axis(cls, v: list[float]) -> list[float]:
        if len(v) != 3 or not any(v):
            raise ValueError("must be a nonzero 3-vector")
        return v


class Shaft(_Body):
    """``Model.add_shaft`` plus the shaft's disks and bearings."""

    positions: VecLength
    outer_diameter: ShaftDiameter | None = None
    inner_diameter: ShaftBore = [0.0]
    outer_diameter_right: ShaftDiameter | None = None
    inner_diameter_right: ShaftBore | None = None
    elastic_modulus: VecPressurePos | None = None
    poisson_ratio: list[Annotated[float, Field(gt=-1.0, lt=0.5)]] | float | None = None
    shear_modulus: VecPressurePos | None = None
    density: VecDensityNonNeg | None = None
    material: Material | None = None
    material_damping: TimeNonNeg = 0.0
    origin: VecLength = [0.0, 0.0, 0.0]
    section: Section | None = None
    layers: list[ShaftLayer] = []


class RigidBody(_Body):
    """``Model.add_rigid_body`` plus its disks (unbalance) and bearings."""

    position: VecLength
    mass: MassPos
    inertia: list[Any]

    @field_validator("inertia")
    @classmethod
    def _inertia(cls, value: list[Any]) -> list[Any] | None:
        return inertia_matrix(value, definite=True)


class CondensedBody(_Body):
    """``Model.add_condensed_body`` from a matrix file, plus its disks and bearings.

    ``path``: a ``.npz`` with ``M``, ``K`` (optional ``D``, ``G``, ``frame``) in SI units, over
    the nodes at ``positions`` (node-major, 6 DOF each); relative to the model file. A
    Craig-Bampton body saved by ``rheolin.fe.CondensedFE.save`` (or ``rheolin condense``)
    carries its ``positions`` and modal DOFs; ``positions`` may then be left out.
    """

    positions: list[VecLength] | None = None
    path: str
    frame: list[list[float]] | None = None


class TransmissionError(_Strict):
    """One harmonic ``amplitude cos(harmonic W_mesh t + phase)`` of the static TE; harmonic
    0 is a constant offset ``amplitude cos(phase)`` (phase 0 or 180 deg)."""

    harmonic: int = Field(ge=0, strict=True)
    amplitude: LengthNonNeg
    phase: Angle = 0.0


class Mesh(_Strict):
    """``Model.add_gear_mesh``."""

    name: Name
    pinion_body: Name
    pinion_node: Index
    gear_body: Name
    gear_node: Index
    pinion_teeth: int = Field(ge=1, strict=True)
    gear_teeth: int = Field(ge=1, strict=True)
    module: LengthPos
    pressure_angle: PressureAngle = float(np.radians(20.0))
    helix_angle: HelixAngle = 0.0
    stiffness: StiffnessNonNeg | None = None
    contact_ratio: float | None = Field(default=None, ge=1.0, le=2.0)
    single_stiffness: StiffnessNonNeg | None = None
    double_stiffness: StiffnessNonNeg | None = None
    stiffness_harmonics: int = Field(default=10, ge=0, le=MAX_STIFFNESS_HARMONICS, strict=True)
    damping: DampingNonNeg = 0.0
    transmission_error: list[TransmissionError] = []
    side: Literal[1, -1] = 1
    load_law: Literal["iso6336", "table"] | None = None
    face_width: LengthPos | None = None
    load_forces: VecForceNonNeg | None = None
    load_stiffness: VecStiffnessPos | None = None

    @model_validator(mode="after")
    def _load_law(self) -> Mesh:
        if self.load_law == "iso6336" and self.face_width is None:
            raise ValueError("load_law = 'iso6336' needs `face_width`")
        if self.load_law == "table" and (self.load_forces is None or self.load_stiffness is None):
            raise ValueError("load_law = 'table' needs `load_forces` and `load_stiffness`")
        if self.load_law is None and (
            self.face_width is not None
            or self.load_forces is not None
            or self.load_stiffness is not None
        ):
            raise ValueError("`face_width`, `load_forces`, `load_stiffness` need `load_law`")
        return self


class Force(_Strict):
    """``Model.add_force``: ``F cos(order W_ref t + phase)``."""

    name: Name
    body: Name
    node: Index
    force: VecForce = [0.0, 0.0, 0.0]
    moment: VecMoment = [0.0, 0.0, 0.0]
    order: Ratio = "0"
    phase: Angle = 0.0
    reference_body: Name | None = None
    offset: VecLength | None = None


class ModelInfo(_Strict):
    """``[model]``: name, input body, default operating speed, gravity."""

    name: str = ""
    description: str = ""
    input_body: Name | None = None
    speed: SpeedPos | None = None
    gravity: VecAcceleration | None = None
    unbalance_reference: list[float] | None = None

    @field_validator("unbalance_reference")
    @classmethod
    def _reference(cls, value: list[float] | None) -> list[float] | None:
        if value is not None and (len(value) != 3 or not all(np.isfinite(value)) or not any(value)):
            raise ValueError("must be a nonzero direction [x, y, z] (global axes)")
        return value


class HarmonicsInfo(_Strict):
    """``[harmonics]``: closure order and cut-off (in orders of the input speed)."""

    order: int = Field(default=2, ge=0, strict=True)
    max_order: float | None = Field(default=None, gt=0)


class RigidLink(_Strict):
    """``Model.add_rigid_link``: ``other_node`` follows ``node`` rigidly (eliminated)."""

    name: Name
    body: Name
    node: Index
    other_body: Name
    other_node: Index
    components: Components | None = None


class ModelFile(_Strict):
    """The whole file."""

    model: ModelInfo = ModelInfo()
    harmonics: HarmonicsInfo = HarmonicsInfo()
    shafts: list[Shaft] = []
    rigid_bodies: list[RigidBody] = []
    condensed_bodies: list[CondensedBody] = []
    meshes: list[Mesh] = []
    forces: list[Force] = []
    torques: list[Torque] = []
    rigid_links: list[RigidLink] = []
    planetary: list[Planetary] = []


def table_class(annotation: Any) -> Any:
    """The table (pydantic model) inside a field's type, e.g. ``Shaft`` in ``list[Shaft]``;
    None for a plain value."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = table_class(arg)
        if found is not None:
            return found
    return None


def field_path(location: Sequence[Any]) -> str:
    """``("shafts", 0, "bearings", 1, "stiffness")`` -> ``"shafts[0].bearings[1].stiffness"``.

    >>> field_path(("shafts", 0, "bearings", 1, "stiffness"))
    'shafts[0].bearings[1].stiffness'
    """
    out = ""
    for part in location:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out
