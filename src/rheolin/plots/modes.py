"""Mode-shape plots: each mode as lines along the shafts' axes, one panel per mode.

Lateral and coupled modes: the orbit size (major semi-axis) of every node against its
position along the axis, with the orbit itself drawn at the node, blue where it whirls
forward (with its body's spin), red backward, grey where it is planar (a line: no whirl) or
the body does not spin. Torsional and axial modes: the twist or axial displacement.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..mechanics.rotation import transverse_basis
from ._common import new_figure, save

__all__ = ["MAX_MODES", "mode_shapes_figure", "plot_mode_shapes"]

HZ = 1.0 / (2.0 * np.pi)

#: At most this many modes in one figure (a 4 x 4 grid).
MAX_MODES = 16
#: A node whose orbit's minor/major axis ratio is below this is drawn planar (grey).
PLANAR = 0.1
WHIRL_COLOURS = {"forward": "tab:blue", "backward": "tab:red", "planar": "0.55"}
STYLES = ("-", "--", ":", "-.")


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


def orbit_axes(xa: np.ndarray, xb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Major and minor semi-axes of the ellipses ``Re((xa, xb) e^{i t})``.

    >>> [float(v[0]) for v in orbit_axes(np.array([1.0]), np.array([-0.5j]))]
    [1.0, 0.5]
    """
    s = np.abs(xa) ** 2 + np.abs(xb) ** 2
    d = np.abs(xa**2 + xb**2)
    return np.sqrt(0.5 * (s + d)), np.sqrt(np.maximum(0.5 * (s - d), 0.0))


def _whirl(xa: complex, xb: complex, spin: int, major: float, minor: float) -> str:
    """``forward``, ``backward`` or ``planar`` for one node's orbit (``(a, b)`` the body's
    transverse basis, right-handed about its axis)."""
    if spin == 0 or major == 0 or minor < PLANAR * major:
        return "planar"
    turn = abs(xa + 1j * xb) - abs(xa - 1j * xb)  # > 0: turns positively about the axis
    return "forward" if turn * spin > 0 else "backward"


def _lateral(ax: Any, motion: dict, model: Any, spin: dict) -> None:
    """Orbit size along each body's axis, with every node's orbit drawn at the node."""
    rows = {}
    for name, (pos, u, _) in motion.items():
        e = np.asarray(model.bodies[name].axis, float)
        a, b = transverse_basis(e)
        xa, xb = u @ a, u @ b
        rows[name] = (pos @ e, xa, xb, *orbit_axes(xa, xb))
    top = max(float(r[3].max(initial=0.0)) for r in rows.values()) or 1.0
    s_all = np.concatenate([r[0] for r in rows.values()])
    gx = 0.04 * max(float(np.ptp(s_all)), 1e-9)
    gy = 0.09
    t = np.linspace(0.0, 2 * np.pi, 41)
    for k, (name, (s, xa, xb, major, minor)) in enumerate(rows.items()):
        if not np.any(major > 1e-6 * top):
            continue
        y = major / top
        ax.plot(s, y, STYLES[k % len(STYLES)], color="k", lw=1.1, label=name)
        for i in range(s.size):
            if major[i] < 1e-2 * top:
                continue
            kind = _whirl(xa[i], xb[i], spin.get(name, 0), major[i], minor[i])
            ring = np.exp(1j * t)
            ax.plot(
                s[i] + gx * (xa[i] * ring).real / top,
                y[i] + gy * (xb[i] * ring).real / top,
                color=WHIRL_COLOURS[kind],
                lw=1.0,
            )
    ax.set_ylim(-0.12, 1.18)
    ax.set_ylabel("orbit size (normalized)", fontsize=8)


def _line(ax: Any, motion: dict, model: Any, kind: str) -> None:
    """Twist (torsional) or axial displacement of each body against its axial coordinate."""
    top = 0.0
    for name, (_, u, phi) in motion.items():
        e = np.asarray(model.bodies[name].axis, float)
        top = max(top, float(np.abs((phi if kind == "torsional" else u) @ e).max(initial=0.0)))
    k = 0
    for name, (pos, u, phi) in motion.items():
        e = np.asarray(model.bodies[name].axis, float)
        vec = (phi if kind == "torsional" else u) @ e
        if not np.any(np.abs(vec) > 1e-6 * max(top, 1e-300)):
            continue
        big = int(np.argmax(np.abs(vec)))
        phase = np.exp(-1j * np.angle(vec[big]))  # the largest motion real
        ax.plot(
            pos @ e,
            (vec * phase).real / max(top, 1e-300),
            STYLES[k % len(STYLES)] + "o",
            color="k",
            ms=3,
            lw=1.1,
            label=name,
        )
        k += 1
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set_ylim(-1.15, 1.15)
    ax.set_ylabel("twist (normalized)" if kind == "torsional" else "axial (normalized)", fontsize=8)


def mode_shapes_figure(model: Any, speed: float, *, n_modes: int = 12, first: int = 0) -> Figure:
    """Modes ``first .. first + n_modes - 1`` (at most :data:`MAX_MODES`) of ``model`` at
    ``speed`` [rad/s] (see the module docstring). Titles give the damped frequency, the
    damping ratio and the kind (:func:`~rheolin.stability.modes.mode_kind`)."""
    from ..stability.modes import averaged_modes, mode_energy, mode_kind, whirl_ratio

    a = model.assemble(float(speed))
    count = min(int(n_modes), MAX_MODES)
    modes = averaged_modes(a.system, first + count)
    axes = {b: model.bodies[b].axis for b in model.bodies}
    ratio = whirl_ratio(modes.shapes, a.dof_labels, axes, a.plan.spin)
    kinds = mode_kind(mode_energy(modes.shapes, a.dof_labels, axes, a.system.M[0]), ratio)
    picks = list(range(first, modes.eigenvalues.size))[:count]
    cols = 3 if len(picks) <= 6 else 4
    rows = max(math.ceil(len(picks) / cols), 1)
    fig, grid = new_figure(rows, cols, (3.9 * cols, 3.0 * rows + 1.1))
    lateral = False
    for slot, ax in enumerate(grid.ravel()):
        if slot >= len(picks):
            ax.set_visible(False)
            continue
        m = picks[slot]
        kind = str(kinds[m])
        zeta = float(modes.damping_ratio[m])
        zeta = 0.0 if abs(zeta) < 1e-12 else zeta  # an undamped mode: rounding only
        motion = _node_motion(modes.shapes[:, m], a.dof_labels, model)
        if kind in ("torsional", "axial"):
            _line(ax, motion, model, kind)
        else:
            _lateral(ax, motion, model, a.plan.spin)
            lateral = True
        ax.set_title(
            f"mode {m}: {modes.frequency[m] * HZ:.2f} Hz, ζ {zeta:.3g}\n{kind}", fontsize=9
        )
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3)
        if slot // cols == rows - 1 or slot + cols >= len(picks):
            ax.set_xlabel("position along the axis [m]", fontsize=8)
    rpm = float(speed) * 30 / np.pi
    bodies = [b for b in model.bodies]
    handles = [
        Line2D([], [], ls=STYLES[k % len(STYLES)], color="k", label=b) for k, b in enumerate(bodies)
    ]
    if lateral:
        handles += [
            Line2D([], [], marker="o", ls="", mfc="none", mec=c, ms=8, label=f"orbit: {k}")
            for k, c in WHIRL_COLOURS.items()
        ]
    fig.legend(handles=handles, loc="outside lower center", ncol=min(len(handles), 6), fontsize=8)
    fig.suptitle(f"mode shapes at {rpm:.0f} rpm (time-averaged system)", fontsize=11)
    return fig


def plot_mode_shapes(
    model: Any, speed: float, path: str | Path, *, n_modes: int = 12, first: int = 0
) -> Path:
    """The modes of ``model`` at ``speed`` [rad/s] as a PNG (:func:`mode_shapes_figure`).

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
    return save(mode_shapes_figure(model, speed, n_modes=n_modes, first=first), path)
