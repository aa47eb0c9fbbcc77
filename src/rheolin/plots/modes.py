"""Mode-shape plots: deflected shaft lines and whirl orbits along the shafts (3-D), twist and
axial lines for torsional and axial modes."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ._common import new_figure, save

__all__ = ["plot_mode_shapes"]

HZ = 1.0 / (2.0 * np.pi)

#: At most this many modes in one figure (a 2 x 3 grid).
MAX_MODES = 6

#: The largest drawn displacement, as a share of the model's largest extent.
DRAWN_AMPLITUDE = 0.12


def _node_motion(
    shape: np.ndarray, labels: list[tuple[str, int, str]], model: Any
) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per body: node positions ``(k, 3)``, translations ``(k, 3)`` and rotations ``(k, 3)``
    (complex, global axes) of one mode shape."""
    index = {lab: i for i, lab in enumerate(labels)}
    out = {}
    for name, body in model.bodies.items():
        pos = np.asarray(body.positions, dtype=float)
        u = np.zeros((pos.shape[0], 3), complex)
        phi = np.zeros((pos.shape[0], 3), complex)
        for k in range(pos.shape[0]):
            for j, c in enumerate(("ux", "uy", "uz")):
                i = index.get((name, k, c))
                u[k, j] = shape[i] if i is not None else 0.0
            for j, c in enumerate(("phix", "phiy", "phiz")):
                i = index.get((name, k, c))
                phi[k, j] = shape[i] if i is not None else 0.0
        out[name] = (pos, u, phi)
    return out


def plot_mode_shapes(
    model: Any, speed: float, path: str | Path, *, n_modes: int = MAX_MODES, first: int = 0
) -> Path:
    """The lowest modes of ``model`` at ``speed`` [rad/s] as a PNG (a 2 x 3 grid).

    Lateral and coupled modes in 3-D: the bodies' axes (grey), the deflected line at one
    instant (black) and the orbit each node describes over a period, blue where it whirls
    forward (with the body's spin) and red where backward. Torsional and axial modes as
    their twist or axial displacement against the position along each body's axis. Titles
    give the damped frequency, the damping ratio and the kind
    (:func:`~rheolin.stability.modes.mode_kind`). Modes ``first .. first + n_modes - 1``.

    >>> import numpy as np, tempfile, pathlib, rheolin as rl
    >>> m = rl.Model()
    >>> m.add_shaft("s", np.linspace(0, 1, 5), outer_diameter=0.05, material="steel")
    >>> m.add_disk("s", 2, outer_diameter=0.3, width=0.05, material="steel")
    >>> for k in (0, 4):
    ...     m.add_bearing(f"b{k}", "s", k, stiffness=1e7, damping=100.0)
    >>> p = plot_mode_shapes(m, 300.0, pathlib.Path(tempfile.mkdtemp()) / "m.png")
    >>> p.stat().st_size > 10000
    True
    """
    from ..stability.modes import (
        averaged_modes,
        mode_energy,
        mode_kind,
        planetary_kinds,
        whirl_ratio,
    )

    a = model.assemble(float(speed))
    modes = averaged_modes(a.system, first + min(int(n_modes), MAX_MODES))
    axes = {b: model.bodies[b].axis for b in model.bodies}
    ratio = whirl_ratio(modes.shapes, a.dof_labels, axes, a.plan.spin)
    kinds = mode_kind(mode_energy(modes.shapes, a.dof_labels, axes, a.system.M[0]), ratio)
    kinds = planetary_kinds(kinds, modes.shapes, model, a)
    picks = list(range(first, modes.eigenvalues.size))[:MAX_MODES]
    fig, grid = new_figure(2, 3, (13, 8))
    for a_ in grid.ravel():
        a_.remove()
    every = np.concatenate([np.asarray(b.positions, float) for b in model.bodies.values()])
    extent = max(float(np.ptp(every, axis=0).max()), 1e-6)
    for slot, m in enumerate(picks):
        kind = str(kinds[m])
        zeta = float(modes.damping_ratio[m])
        zeta = 0.0 if abs(zeta) < 1e-12 else zeta  # an undamped mode: rounding only
        title = f"mode {m}: {modes.frequency[m] * HZ:.2f} Hz, zeta {zeta:.3g}\n{kind}"
        motion = _node_motion(modes.shapes[:, m], a.dof_labels, model)
        if kind in ("torsional", "axial"):
            ax = fig.add_subplot(2, 3, slot + 1)
            _plot_line(ax, motion, model, kind)
        else:
            ax = fig.add_subplot(2, 3, slot + 1, projection="3d")
            _plot_orbits(ax, motion, model, a.plan.spin, extent)
        ax.set_title(title, fontsize=9)
    rpm = float(speed) * 30 / np.pi
    fig.suptitle(f"mode shapes at {rpm:.0f} rpm (time-averaged system)", fontsize=11)
    return save(fig, path)


def _plot_line(ax: Any, motion: dict, model: Any, kind: str) -> None:
    """Twist (torsional) or axial displacement of each body against its axial coordinate."""
    top = 0.0
    for name, (_, u, phi) in motion.items():
        e = np.asarray(model.bodies[name].axis, float)
        vec = phi if kind == "torsional" else u
        top = max(top, float(np.abs(vec @ e).max(initial=0.0)))
    for name, (pos, u, phi) in motion.items():
        e = np.asarray(model.bodies[name].axis, float)
        vec = (phi if kind == "torsional" else u) @ e
        if not np.any(np.abs(vec) > 1e-9 * max(top, 1e-300)):
            continue
        z = pos @ e
        k = int(np.argmax(np.abs(vec)))
        phase = np.exp(-1j * np.angle(vec[k]))  # the largest motion real
        ax.plot(z, (vec * phase).real / max(top, 1e-300), "-o", ms=3, label=name)
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set_xlabel("position along the axis [m]")
    ax.set_ylabel("twist (normalized)" if kind == "torsional" else "axial displacement (norm.)")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)


def _plot_orbits(ax: Any, motion: dict, model: Any, spin: dict, extent: float) -> None:
    """Deflected lines and node orbits in 3-D, the drawn amplitude scaled to the model."""
    top = max(float(np.abs(u).max(initial=0.0)) for _, u, _ in motion.values())
    scale = DRAWN_AMPLITUDE * extent / max(top, 1e-300)
    t = np.linspace(0.0, 2 * np.pi, 49)
    for name, (pos, u, _) in motion.items():
        e = np.asarray(model.bodies[name].axis, float)
        ax.plot(*pos.T, color="0.6", lw=0.8)
        line = pos + scale * u.real
        ax.plot(*line.T, color="k", lw=1.4)
        s = spin.get(name, 0)
        for k in range(pos.shape[0]):
            orbit = pos[k] + scale * np.real(np.outer(np.exp(1j * t), u[k]))
            # whirl of this node: the sense of rotation of its orbit about the body's axis
            turn = float(np.dot(np.cross(u[k].real, u[k].imag), e))
            turn = -turn  # Re(u e^{i t}) turns from Re u towards -Im u
            fwd = turn * (1 if s >= 0 else -1) > 0
            color = "tab:blue" if fwd else "tab:red"
            if s == 0 or np.abs(u[k]).max() < 1e-2 * top:
                color = "0.4"  # a body that does not spin, or a node at rest (a nodal point)
            ax.plot(*orbit.T, color=color, lw=0.9)
            ax.plot(*line[k], "o", color=color, ms=2.5)
    ax.set_xlabel("x [m]", fontsize=7)
    ax.set_ylabel("y [m]", fontsize=7)
    ax.set_zlabel("z [m]", fontsize=7)
    ax.tick_params(labelsize=6)
