"""The records of an operating point: each load-dependent bearing and mesh at the static
equilibrium, and the equilibrium itself with the model linearized there.

>>> import numpy as np
>>> b = BearingState(np.array([0.0, -1e-5, 0.0]), np.array([0.0, -300.0, 0.0]),
...                  np.diag([2e7, 3e7, 0.0]), in_contact=4, elements=9)
>>> b.load
300.0
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["BearingState", "MeshState", "OperatingPoint"]


@dataclass
class BearingState:
    """A load-dependent bearing at the operating point (global axes)."""

    deflection: np.ndarray  #: radial deflection of the node relative to its support [m] (3)
    force: np.ndarray  #: force on the support [N] (3)
    stiffness: np.ndarray  #: tangent (operating) stiffness [N/m] (3 x 3)
    in_contact: int  #: rolling elements in contact (1/0 for lumped laws)
    elements: int  #: rolling elements (0 for lumped laws)

    @property
    def load(self) -> float:
        return float(np.linalg.norm(self.force))


@dataclass
class MeshState:
    """A load-dependent gear mesh at the operating point (line of action)."""

    force: float  #: mean mesh force [N]
    deflection: float  #: mean mesh deflection [m]
    secant: float  #: k(F) [N/m]
    stiffness: float  #: tangent (operating) stiffness dF/d delta [N/m]
    nominal: float  #: nominal mean stiffness k0 [N/m]


@dataclass
class OperatingPoint:
    """Static equilibrium of a preloaded model and the model linearized there."""

    speed: float
    displacement: np.ndarray  #: static displacement of every DOF
    dof_labels: list[tuple[str, int, str]]
    node_index: dict[tuple[str, int], int]
    bearings: dict[str, BearingState]
    meshes: dict[str, MeshState]
    torques: dict[str, float]  #: every torque [N m], reactions computed
    rigid_load: np.ndarray  #: load left on the free rigid-body motions (R^T f), held
    iterations: int
    load_steps: int
    residual: float  #: relative residual of the equilibrium
    model: Any  #: the linearized :class:`~rheolin.mechanics.model.Model`
    info: dict[str, Any] = field(default_factory=dict)

    def node_displacement(self, body: str, node: int) -> np.ndarray:
        """``(ux, uy, uz, phix, phiy, phiz)`` of a node at the operating point."""
        i = self.node_index[(body, node)]
        return self.displacement[6 * i : 6 * i + 6].copy()

    def max_displacement(self) -> tuple[float, tuple[str, int]]:
        """The largest translation [m] of any node, and where."""
        best, where = 0.0, ("", -1)
        for key, i in self.node_index.items():
            v = float(np.linalg.norm(self.displacement[6 * i : 6 * i + 3]))
            if v > best:
                best, where = v, key
        return best, where

    def to_dict(self) -> dict[str, Any]:
        """A JSON-able summary (SI units)."""
        peak, (body, node) = self.max_displacement()
        return {
            "speed_rad_s": self.speed,
            "max_displacement_m": peak,
            "max_displacement_at": {"body": body, "node": node},
            "bearings": {
                k: {
                    "load_N": b.load,
                    "force_N": b.force.tolist(),
                    "deflection_m": b.deflection.tolist(),
                    "stiffness_N_per_m": b.stiffness.tolist(),
                    "in_contact": b.in_contact,
                    "elements": b.elements,
                }
                for k, b in self.bearings.items()
            },
            "meshes": {
                k: {
                    "force_N": m.force,
                    "deflection_m": m.deflection,
                    "stiffness_N_per_m": m.stiffness,
                    "secant_N_per_m": m.secant,
                    "nominal_N_per_m": m.nominal,
                }
                for k, m in self.meshes.items()
            },
            "torques_N_m": dict(self.torques),
            "rigid_load": self.rigid_load.tolist(),
            "iterations": self.iterations,
            "load_steps": self.load_steps,
            "residual": self.residual,
        }

    def summary(self) -> list[str]:
        """Lines for a terminal summary."""
        peak, (body, node) = self.max_displacement()
        lines = [
            f"operating point: static equilibrium in {self.iterations} Newton iterations, "
            f"{self.load_steps} load step{'s' if self.load_steps > 1 else ''}, "
            f"relative residual {self.residual:.1e}; largest static deflection "
            f"{peak * 1e6:.3g} um at {body} node {node}"
        ]
        for k, t in self.torques.items():
            lines.append(f"  torque {k}: {t:.6g} N m")
        for k, b in self.bearings.items():
            kt = np.linalg.eigvalsh(0.5 * (b.stiffness + b.stiffness.T))
            contact = f", {b.in_contact} of {b.elements} elements in contact" if b.elements else ""
            lines.append(
                f"  bearing {k}: load {b.load:.6g} N, deflection "
                f"{np.linalg.norm(b.deflection) * 1e6:.4g} um, operating stiffness "
                f"{kt[-1]:.4g} / {kt[-2]:.4g} N/m (principal){contact}"
            )
        for k, m in self.meshes.items():
            lines.append(
                f"  mesh {k}: force {m.force:.6g} N, deflection {m.deflection * 1e6:.4g} um, "
                f"operating stiffness {m.stiffness:.4g} N/m ({m.stiffness / m.nominal:.3g} x "
                "nominal)"
            )
        if np.abs(self.rigid_load).max(initial=0.0) > 0:
            lines.append(
                "  load held by the constant-speed constraint (unbalanced torques): R^T f = "
                + ", ".join(f"{x:.3g}" for x in self.rigid_load)
            )
        return lines
