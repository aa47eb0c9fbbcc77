"""The models an operating point is built from and gives: the linear part of a preloaded model
(:func:`base_model`), the model linearized at the equilibrium (:func:`linearized_model`), both
replayed from the model's own calls, and the speed templates of preloaded models.

>>> import rheolin as rl
>>> m = rl.Model()
>>> m.add_rigid_body("r", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
>>> m.add_bearing("b", "r", 0, stiffness=1e6, components=None)
>>> m.add_torque("input", "r", 0, 2.0)
>>> base = base_model(m)
>>> type(base) is type(m), sorted(base.forces), base.preloaded
(True, ['input'], False)
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np

from ...errors import ModelError
from ..items import ModelData
from ..joints import COMPONENTS
from ..template import SpeedTemplate, model_speed_plan
from .state import BearingState, MeshState

__all__ = [
    "base_model",
    "linearized",
    "linearized_model",
    "preloaded_template",
    "replay",
    "speed_independent",
]

_D = TypeVar("_D", bound=ModelData)
Calls = list[tuple[str, dict[str, Any]]]

_MESH_LAW_ARGS = ("load_law", "face_width", "load_forces", "load_stiffness")


def replay(model: _D, replace: Callable[[str, dict[str, Any]], Calls]) -> _D:
    """A new model of the same type, built from ``model``'s calls, each replaced by the calls
    ``replace(method, arguments)`` returns."""
    out = type(model)(input_body=model.input_body, unbalance_reference=model.unbalance_reference)
    for method, kwargs in model.calls:
        for name, kw in replace(method, kwargs):
            getattr(out, name)(**kw)
    return out


def _torque_force(model: ModelData, kw: dict[str, Any], value: float) -> tuple[str, dict[str, Any]]:
    axis = np.asarray(model.bodies[kw["body"]].axis, dtype=float)
    return "add_force", dict(
        name=kw["name"], body=kw["body"], node=kw["node"], moment=list(value * axis)
    )


def base_model(model: _D) -> _D:
    """The linear part: no load-dependent bearings, nominal meshes, given torques as moments."""

    def replace(method: str, kw: dict[str, Any]) -> Calls:
        if method == "add_rolling_bearing":
            return []
        if method == "add_torque":
            t = model.torques[kw["name"]]["torque"]
            return [] if isinstance(t, str) else [_torque_force(model, kw, t)]
        if method == "add_gear_mesh":
            return [(method, {k: v for k, v in kw.items() if k not in _MESH_LAW_ARGS})]
        return [(method, kw)]

    return replay(model, replace)


def linearized_model(
    model: _D,
    bstates: dict[str, BearingState],
    damping: dict[str, np.ndarray],
    mstates: dict[str, MeshState],
    torques: dict[str, float],
) -> _D:
    """The model linearized at the equilibrium: each bearing a linear joint with its tangent
    stiffness, radial ``damping`` and preload, each mesh scaled to its operating stiffness,
    every torque (reactions solved) a static moment."""

    def replace(method: str, kw: dict[str, Any]) -> Calls:
        if method == "add_rolling_bearing":
            st = bstates[kw["name"]]
            b = model.rolling[kw["name"]]
            preload = st.force - st.stiffness @ st.deflection
            other_body, other_node = b["other"]
            return [
                (
                    "add_bearing",
                    dict(
                        name=kw["name"],
                        body=b["body"],
                        node=b["node"],
                        stiffness=st.stiffness,
                        damping=damping[kw["name"]],
                        components=list(COMPONENTS[:3]),
                        other_body=other_body,
                        other_node=other_node,
                        preload=preload,
                    ),
                )
            ]
        if method == "add_torque":
            return [_torque_force(model, kw, torques[kw["name"]])]
        if method == "add_gear_mesh":
            kw = {k: v for k, v in kw.items() if k not in _MESH_LAW_ARGS}
            ms = mstates.get(kw["name"])
            if ms is None:
                return [(method, kw)]
            g = model.meshes[kw["name"]]
            ratio = ms.stiffness / ms.nominal
            te = dict(g["transmission_error"] or {})
            te[0] = te.get(0, 0.0) + (ms.deflection - ms.force / ms.stiffness)
            # the stiffness function scaled as it was given (a mean, a Fourier series, or the
            # rectangular wave's two levels): the model file can still say it
            given = kw.get("stiffness")
            if given is not None:
                kw["stiffness"] = (
                    {j: v * ratio for j, v in given.items()}
                    if isinstance(given, dict)
                    else given * ratio
                )
            for key in ("single_stiffness", "double_stiffness"):
                if kw.get(key) is not None:
                    kw[key] = kw[key] * ratio
            kw["transmission_error"] = te
            return [(method, kw)]
        return [(method, kw)]

    return replay(model, replace)


# --------------------------------------------------------------------------- templates
class _PerSpeedTemplate:
    """A preloaded model whose static stiffness changes with the speed: linearized at each
    speed (the operating point is cached per speed on the model)."""

    time_invariant = False

    def __init__(self, model: ModelData) -> None:
        self.model = model
        self.plan = model_speed_plan(model)

    def assemble(self, speed: float) -> Any:
        return self.model.operating_point(speed).model.assemble(speed)


def speed_independent(model: ModelData) -> bool:
    """True when the static problem of a preloaded model does not depend on the speed (no
    speed tables, no speed-dependent mean stiffness or static load): one operating point
    serves every speed."""
    return not SpeedTemplate(base_model(model)).static_depends_on_speed()


def linearized(model: _D) -> _D:
    """The model linearized at its operating point, for analyses over speed that edit or
    inspect a model's joints (the critical-speed map); a model that is not preloaded is
    returned as it is. Refused when the operating point changes with the speed."""
    if not model.preloaded:
        return model
    if not speed_independent(model):
        raise ModelError(
            "this preloaded model's operating point changes with the speed (speed-dependent "
            "stiffness or static load): use the Campbell diagram (rheolin campbell), which "
            "linearizes at every speed"
        )
    return model.operating_point(1.0).model


def preloaded_template(model: ModelData) -> Any:
    """``model.speed_template()`` of a preloaded model: one linearization when its static
    problem does not depend on the speed, else one per speed."""
    if speed_independent(model):
        return model.operating_point(1.0).model.speed_template()
    return _PerSpeedTemplate(model)
