"""The rigid motions of a model's bodies, and which of them a steady state may hold.

A rigid-body mode of the mean stiffness (:mod:`rheolin.system.rigid_modes`) is a motion that
nothing resists. The operating point of rotordynamics presumes that two kinds are held: each
body's rotation about its own axis (the drive holds the speed: the constant-speed
assumption) and its translation along that axis (a thrust bearing, or the drive's coupling,
holds the axial position). Anything else -- a shaft that no bearing holds laterally, a body
free to tilt -- has no steady state: a load moves it without bound, and its response is not
"held" by anything physical. :class:`Motions`, which a model's assembly attaches to its
system (``system.motions``), knows each body's nodes and axis, so the solvers can tell the
two apart and name the body and the direction of a motion nothing holds.

>>> import numpy as np
>>> m = Motions.of_bodies({"r": (np.array([0.0, 0.0, 1.0]), np.zeros((1, 3)), [np.arange(6)])},
...                       [("r", 0, c) for c in ("ux", "uy", "uz", "phix", "phiy", "phiz")])
>>> spin = np.array([[0, 0, 0, 0, 0, 1.0]]).T   # rotation about the axis: held
>>> m.unheld(spin)
[]
>>> side = np.array([[1.0, 0, 0, 0, 0, 0]]).T   # lateral translation: nothing may hold it
>>> [u.describe() for u in m.unheld(side)]
["body 'r' moves laterally (ux)"]
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import scipy.sparse as sp

__all__ = ["HELD_SHARE", "FreeMotion", "Motions"]

#: A direction of the rigid-body modes is held when at most this share of it (2-norm) lies
#: outside the held motions (exact rigid motions differ from them by round-off only).
HELD_SHARE = 1e-4

#: Names of a body's six rigid motions in its own axes (axis last).
_KINDS = ("lateral", "lateral", "axial", "tilt", "tilt", "spin")


@dataclass(frozen=True)
class FreeMotion:
    """A rigid motion that nothing holds: the body it moves most and how."""

    body: str
    kinds: tuple[str, ...]  #: "lateral", "tilt", "axial", "spin" (most first)
    components: tuple[str, ...]  #: the DOF components it moves most (global names)
    vector: np.ndarray | None = None  #: the motion on the full DOFs (unit 2-norm)

    def describe(self) -> str:
        """``"body 'rotor' moves laterally (ux, uy)"``."""
        verbs = {"lateral": "moves laterally", "tilt": "tilts", "axial": "moves axially",
                 "spin": "turns about its axis"}  # fmt: skip
        what = " and ".join(dict.fromkeys(verbs[k] for k in self.kinds))
        return f"body {self.body!r} {what} ({', '.join(self.components)})"


def _frame(axis: np.ndarray) -> np.ndarray:
    """Orthonormal body axes (columns: across, across, along ``axis``)."""
    e = np.asarray(axis, float) / np.linalg.norm(axis)
    t = np.eye(3)[int(np.argmin(np.abs(e)))]
    a = np.cross(e, t)
    a /= np.linalg.norm(a)
    return np.column_stack([a, np.cross(e, a), e])


@dataclass
class Motions:
    """The bodies of a system's DOFs: labels, and each body's six rigid motions.

    Attributes
    ----------
    labels
        ``(body, node, component)`` of every DOF of the full (unreduced) system.
    rigid
        ``{body: (rows, R_b)}``: the body's rigid motions on its DOFs ``rows`` (``R_b``:
        ``len(rows) x 6``; columns: translations across, across and along its axis,
        rotations about the same axes through the centroid of its nodes).
    to_full
        ``q_full = to_full @ q`` for a system reduced by exact constraints (None: the full
        system itself).
    """

    labels: list[tuple[str, int, str]]
    rigid: dict[str, tuple[np.ndarray, np.ndarray]]
    to_full: Any = None

    @classmethod
    def of_bodies(
        cls,
        bodies: dict[str, tuple[np.ndarray, np.ndarray, list[np.ndarray]]],
        labels: list[tuple[str, int, str]],
    ) -> Motions:
        """From ``{body: (axis, node positions (k x 3), node DOFs [6 indices each])}``."""
        rigid: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for name, (axis, positions, dofs) in bodies.items():
            frame = _frame(np.asarray(axis, float))
            pos = np.asarray(positions, float).reshape(-1, 3)
            centre = pos.mean(axis=0)
            rows = np.concatenate([np.asarray(d, dtype=np.int64)[:6] for d in dofs])
            R = np.zeros((rows.size, 6))
            for k, p in enumerate(pos):
                for j in range(3):
                    w = frame[:, j]
                    R[6 * k : 6 * k + 3, j] = w  # translation
                    R[6 * k : 6 * k + 3, 3 + j] = np.cross(w, p - centre)  # off-centre nodes
                    R[6 * k + 3 : 6 * k + 6, 3 + j] = w
            rigid[name] = (rows, R)
        return cls(list(labels), rigid)

    @property
    def n(self) -> int:
        """DOFs of the full system."""
        return len(self.labels)

    def through(self, T: Any) -> Motions:
        """The motions of the system reduced by ``q = T y`` (exact constraints)."""
        full = T if self.to_full is None else sp.csr_array(self.to_full @ T)
        return replace(self, to_full=full)

    def full(self, V: np.ndarray) -> np.ndarray:
        """Vectors of the (reduced) system on the full DOFs."""
        V = np.asarray(V)
        return V if self.to_full is None else np.asarray(self.to_full @ V)

    def _held_part(self, Q: np.ndarray) -> np.ndarray:
        """The projection of ``Q`` (full DOFs, columns) on the held motions: each body's
        translation along and rotation about its axis (orthogonal, on disjoint DOFs)."""
        out = np.zeros_like(Q)
        for rows, R in self.rigid.values():
            for j in (2, 5):
                h = R[:, j] / np.linalg.norm(R[:, j])
                out[rows] += np.outer(h, h @ Q[rows])
        return out

    def unheld(self, modes: np.ndarray) -> list[FreeMotion]:
        """The directions of ``modes`` (rigid-body modes of the system, as columns) that no
        held motion explains, each named by the body it moves most; empty when all are held."""
        V = self.full(np.real(np.asarray(modes, dtype=float)))
        V = V.reshape(self.n, -1)
        if V.shape[1] == 0:
            return []
        Q, _ = np.linalg.qr(V / np.maximum(np.linalg.norm(V, axis=0), 1e-300))
        U, s, Vt = np.linalg.svd(Q - self._held_part(Q), full_matrices=False)
        return [
            replace(self.name(U[:, i]), vector=Q @ Vt[i]) for i in np.flatnonzero(s > HELD_SHARE)
        ]

    def name(self, v: np.ndarray) -> FreeMotion:
        """The body a motion ``v`` (full DOFs) moves most, and how (its rigid motions)."""
        best, coef, top = "", np.zeros(6), -1.0
        for body, (rows, R) in self.rigid.items():
            c, *_ = np.linalg.lstsq(R, v[rows], rcond=None)
            size = float(np.linalg.norm(R @ c))
            if size > top:
                best, coef, top = body, c, size
        rows, R = self.rigid[best]
        share = np.linalg.norm(R * coef, axis=0)
        order = [int(j) for j in np.argsort(-share) if share[j] > 0.1 * share.max()]
        kinds = tuple(dict.fromkeys(_KINDS[j] for j in order))
        part = np.abs(R[:, order] @ coef[order])
        comps = [self.labels[rows[i]][2] for i in np.argsort(-part) if part[i] > 0.1 * part.max()]
        return FreeMotion(best, kinds, tuple(dict.fromkeys(comps)), np.asarray(v, float))

    def held_load(self, v: np.ndarray, work: float) -> tuple[str, str, float, str]:
        """The generalized load ``work`` (``v^T f``) of a held motion ``v`` (full DOFs) in the
        user's units: at the body it turns (or moves axially) most, per radian (N m) or per
        metre (N). Returns ``(body, "rotation" | "axial motion", load, unit)``."""
        best, amount, what = "", 0.0, "rotation"
        for body, (rows, R) in self.rigid.items():
            c, *_ = np.linalg.lstsq(R, v[rows], rcond=None)
            for j, kind in ((5, "rotation"), (2, "axial motion")):
                if abs(c[j]) > abs(amount) * (1 + 1e-9):
                    best, amount, what = body, float(c[j]), kind
        if amount == 0.0:
            return "", what, 0.0, ""
        return best, what, float(work) / amount, "N m" if what == "rotation" else "N"
