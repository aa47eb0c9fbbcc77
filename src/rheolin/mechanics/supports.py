"""Supports of a :class:`~rheolin.mechanics.model.Model`: bearings, seals and couplings,
load-dependent rolling bearings, static torques, and the static operating point the model is
solved about when any of them depends on the load."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import ModelError
from .items import ModelData, positive, recorded
from .joints import bearing_record
from .loads import torque_value
from .planetary_assembly import refuse_in_frames
from .preload import OperatingPoint
from .preload import operating_point as solve_operating_point
from .rolling import rolling_record

__all__ = ["SupportTable"]


class SupportTable(ModelData):
    """The vocabulary of supports (a part of :class:`~rheolin.mechanics.model.Model`)."""

    def __init__(
        self, input_body: str | None = None, unbalance_reference: Sequence[float] | None = None
    ) -> None:
        super().__init__(input_body, unbalance_reference)
        self._operating: dict[tuple[float, int], OperatingPoint] = {}

    @recorded
    def add_bearing(
        self,
        name: str,
        body: str,
        node: int,
        stiffness: Any = 0.0,
        damping: Any = 0.0,
        components: Sequence[str] | None = ("ux", "uy"),
        other_body: str | None = None,
        other_node: int | None = None,
        frame: str | None = None,
        mass: Any = 0.0,
        speeds: Sequence[float] | None = None,
        interpolation: str = "cubic",
        extrapolate: bool = False,
        offset: Sequence[float] | None = None,
        other_offset: Sequence[float] | None = None,
        preload: Sequence[float] | None = None,
    ) -> None:
        """A bearing, seal or coupling from a node to ground (default) or to another body's node.

        ``stiffness`` / ``damping`` / ``mass`` (added mass) act on the relative displacement,
        over ``components`` (names from ``COMPONENTS``; None means all six): a scalar, a
        vector (diagonal) or a matrix (cross-coupling, anisotropy). ``frame=None``: constant
        in the inertial frame; ``frame="<body>"``: defined in that body's rotating axes.

        Speed-dependent coefficients (journal bearings, seals): give ``speeds`` [rad/s of the
        bearing's ``body``] and one coefficient per speed in ``stiffness``, ``damping`` and
        ``mass`` (a scalar is the same at every speed); they are interpolated by
        ``interpolation`` (see :class:`~rheolin.mechanics.bearing_table.SpeedTable`) and
        evaluated at the operating speed by every solver, Campbell diagram and stability map.

        ``offset`` [m] (global axes) puts the bearing at a point that far from the node, rigidly
        attached to it (a bearing seat beside a shaft node, a housing foot off its node): the
        coefficients act on the point's motion ``u + phi x r``, which couples the node's
        translations and tilts exactly; ``other_offset`` likewise on the other body's side.
        Inertial-frame joints only (``frame=None``).

        ``preload`` [N, N m] (global axes): the force (3) or force and moment (6) the joint
        exerts on its support at zero relative displacement, a preloaded spring: it acts as
        ``preload + K delta``; the static load ``-preload`` on the node (``+preload`` on the
        other node) and the reported bearing force include it. A linearized load-dependent
        joint is such a spring (:mod:`rheolin.mechanics.preload`). Constant joints only.

        >>> from rheolin import Model
        >>> m = Model()
        >>> m.add_shaft("s", [0.0, 0.5], outer_diameter=0.05, material="steel")
        >>> m.add_bearing("b", "s", 0, stiffness=[[[1e7, 2e6], [-2e6, 1e7]], [[2e7, 4e6],
        ...               [-4e6, 2e7]]], damping=[1e3, 2e3], speeds=[100.0, 300.0],
        ...               interpolation="linear")
        >>> float(m.bearing_coefficients("b", 200.0)[0][0, 1])
        3000000.0
        """
        self.joint_nodes(name, body, node, other_body, other_node)
        if frame is not None:
            self.body(frame, "frame")
        joint = bearing_record(
            stiffness, damping, mass, components, frame, speeds, interpolation, extrapolate,
            offset, other_offset, other_body is not None, preload,
        )  # fmt: skip
        self.joints[name] = dict(body=body, node=node, other=(other_body, other_node), **joint)

    @recorded
    def add_rolling_bearing(
        self,
        name: str,
        body: str,
        node: int,
        law: str = "elements",
        kind: str = "ball",
        stiffness: float = 0.0,
        elements: int = 0,
        clearance: float = 0.0,
        angle: float = 0.0,
        deflection: Sequence[float] | None = None,
        force: Sequence[float] | None = None,
        damping: float = 0.0,
        other_body: str | None = None,
        other_node: int | None = None,
    ) -> None:
        """A rolling-element bearing whose radial stiffness depends on its load.

        ``law``: ``"elements"`` (``elements`` rolling elements, each with the Hertz law
        ``Q = stiffness <delta - clearance>^n``, ``n`` 3/2 for ``kind="ball"``, 10/9 for
        ``"roller"``; ``angle`` places element 0), ``"radial"`` (one lumped law
        ``|F| = stiffness <|d| - clearance>^n`` for the bearing) or ``"table"`` (radial
        ``force`` [N] against ``deflection`` [m]); see :mod:`rheolin.mechanics.rolling`.
        The force acts in the bearing plane (normal to the body's axis) on the node's motion
        relative to ground or to ``other_node``; ``damping`` [N s/m] is a constant radial
        damping. The model is then solved about its operating point (static equilibrium
        under gravity, static forces and torques; :mod:`~rheolin.mechanics.preload`), where this
        bearing becomes a linear joint with its tangent stiffness.

        >>> from rheolin import Model
        >>> m = Model()
        >>> m.add_shaft("s", [0.0, 0.2], outer_diameter=0.04, material="steel")
        >>> m.add_rolling_bearing("a", "s", 0, kind="ball", stiffness=8e9, elements=9)
        >>> sorted(m.rolling)
        ['a']
        """
        self.joint_nodes(name, body, node, other_body, other_node)
        law_damping = rolling_record(
            law, kind, stiffness, elements, clearance, angle, deflection, force, damping
        )
        self.rolling[name] = dict(
            body=body, node=int(node), other=(other_body, other_node), **law_damping
        )

    @recorded
    def add_torque(self, name: str, body: str, node: int, torque: float | str = "reaction") -> None:
        """A static torque [N m] about the body's axis at a node (positive: right-handed
        about the axis): the input torque, or the output load. ``torque="reaction"``: the
        torque that balances all the others on the free rotation of the drive train (the
        output load of a gearbox driven by a given input torque). The model is then solved
        about its operating point (:mod:`rheolin.mechanics.preload`).

        >>> from rheolin import Model
        >>> m = Model()
        >>> m.add_rigid_body("r", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
        >>> m.add_torque("input", "r", 0, 12.5)
        >>> m.torques["input"]["torque"]
        12.5
        """
        self.new_item(name, self.torques)
        self.node(self.body(body, "body"), node)
        self.torques[name] = dict(body=body, node=int(node), torque=torque_value(torque))

    def operating_point(self, speed: float) -> OperatingPoint:
        """The static equilibrium under the model's static loads and torques at input
        ``speed`` [rad/s], and the model linearized there
        (:class:`rheolin.mechanics.preload.OperatingPoint`); cached per speed."""
        key = (positive(speed, "speed"), len(self.calls))  # a changed model: computed anew
        if key not in self._operating:
            if len(self._operating) > 64:
                self._operating.clear()
            refuse_in_frames(self)
            self._operating[key] = solve_operating_point(self, key[0])
        return self._operating[key]

    def bearing_coefficients(
        self, name: str, speed: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(K, D, M)`` (6x6) of joint ``name`` at its body's ``speed`` [rad/s]."""
        if name not in self.joints:
            raise ModelError(f"`name`: no bearing {name!r}; bearings: {list(self.joints)}")
        j = self.joints[name]
        if j["table"] is not None:
            return j["table"].at(speed)
        return j["K"], j["D"], j["M"]
