"""What drives an instability: the generator, the kind of resonance, the modes.

A growing Floquet exponent of a parametrically excited system has an eigenvector with energy
at harmonic 0 (a mode of the time-averaged system at ``w_j``) and at a partner harmonic ``h``
(the time-averaged mode at ``h`` is what it resonates with). Writing ``h`` as the smallest
integer combination of the model's generators (each gear mesh, the 1x and 2x of each rotating
body) names the source; the modes name the kind:

* the time-averaged system is already unstable: ``rotating damping`` (shaft material
  damping, damping in a rotating frame) or ``circulatory forces`` (time-invariant);
* ``h`` is one generator ``G`` once: **principal** parametric resonance
  (``2 w_j ~ G`` when the partner is mode ``j`` itself, else a combination of two modes
  ``w_j + w_k ~ G`` or ``|w_j - w_k| ~ G``);
* ``h`` is one generator ``k`` times (``k >= 2``): **secondary** resonance (``2 w_j ~ k G``);
* ``h`` involves two or more generators (two meshes, a mesh and a shaft's 2x):
  **combination** resonance (``2 w_j ~ G_1 + G_2``, ...).

The category (``mechanism``) keeps the map's established names: ``"parametric mesh
resonance"`` (meshes only), ``"asymmetric shaft band"`` (rotating bodies only),
``"combined parametric excitation"`` (both), ``"rotating damping"``,
``"circulatory forces (time-invariant)"``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..harmonics.lattice import combination_text, harmonic_lattice

__all__ = [
    "ASYMMETRY",
    "CIRCULATORY",
    "COMBINED",
    "MESH",
    "ROTATING_DAMPING",
    "Mechanism",
    "classify",
    "generator_table",
    "identify",
]

ROTATING_DAMPING = "rotating damping"
CIRCULATORY = "circulatory forces (time-invariant)"
MESH = "parametric mesh resonance"
ASYMMETRY = "asymmetric shaft band"
COMBINED = "combined parametric excitation"
UNIDENTIFIED = "unidentified"

#: Largest number of generator steps tried when decomposing a partner harmonic.
MAX_STEPS = 5


@dataclass(frozen=True)
class Mechanism:
    """The mechanism of an instability.

    Attributes
    ----------
    category
        One of the module's category names.
    resonance
        ``"principal"``, ``"secondary"``, ``"combination"``, ``"time-invariant"`` or ``""``.
    sources
        Names of the generators involved (``"mesh stage1"``, ``"intermediate 2x"``).
    relation
        The frequency relation, e.g. ``"2 x 3626 rad/s ~ mesh stage1 (7226 rad/s)"``.
    exponent
        The growing Floquet exponent [1/s].
    """

    category: str
    resonance: str = ""
    sources: tuple[str, ...] = ()
    relation: str = ""
    exponent: complex = complex("nan")

    @property
    def label(self) -> str:
        """One line for plots and reports."""
        parts = [self.category]
        if self.resonance and self.resonance != "time-invariant":
            parts.append(f"{self.resonance} resonance")
        text = ", ".join(parts)
        return f"{text}: {self.relation}" if self.relation else text

    def to_dict(self) -> dict[str, Any]:
        """Plain data for JSON."""
        return {
            "category": self.category,
            "resonance": self.resonance,
            "sources": list(self.sources),
            "relation": self.relation,
            "label": self.label,
        }


def generator_table(assembled: Any) -> list[tuple[str, int, str]]:
    """``(label, harmonic, kind)`` of every generator of an assembled model.

    Kinds: ``"mesh"`` (a gear mesh's frequency) and ``"body"`` (1x and 2x of every
    rotating body).
    """
    out: list[tuple[str, int, str]] = []
    for name, (_, _, harmonic) in assembled.meshes.items():
        out.append((f"mesh {name}", abs(int(harmonic)), "mesh"))
    for body, spin in assembled.plan.spin.items():
        if spin:
            out.append((f"{body} 1x", abs(int(spin)), "body"))
            out.append((f"{body} 2x", 2 * abs(int(spin)), "body"))
    return out


def _decompose(h: int, table: list[tuple[str, int, str]]) -> np.ndarray | None:
    """Fewest generator steps summing to ``h`` (None beyond :data:`MAX_STEPS`)."""
    gens = [g for _, g, _ in table]
    if not gens or h == 0:
        return None
    lat = harmonic_lattice(gens, MAX_STEPS, max_size=2_000_000)
    try:
        i = lat.position(int(h))
    except KeyError:
        return None
    # map the lattice's generators (sorted, unique) back to the table's order
    coef = np.zeros(len(table), dtype=np.int64)
    for g, a in zip(lat.generators, lat.steps[i], strict=True):
        if a:
            coef[gens.index(g)] = a
    return coef


def _has_rotating_damping(model: Any) -> bool:
    for b in model.bodies.values():
        mat = b.data.get("material")
        if b.kind == "shaft" and mat is not None and mat.damping_beta > 0:
            return True
    return any(j["frame"] is not None and np.any(j["D"]) for j in model.joints.values())


def identify(model: Any, assembled: Any, result: Any) -> Mechanism:
    """The mechanism of the leading exponent of a lattice :class:`~rheolin.FloquetResult`
    of an assembled model (the generators are its meshes and rotating bodies)."""
    return classify(
        result,
        generator_table(assembled),
        assembled.system.omega,
        rotating_damping=_has_rotating_damping(model),
    )


def classify(
    result: Any,
    generators: list[tuple[str, int, str]],
    omega: float,
    *,
    rotating_damping: bool = False,
) -> Mechanism:
    """The mechanism of the leading exponent of a lattice :class:`~rheolin.FloquetResult`.

    Parameters
    ----------
    result
        From the lattice method (it carries the partner harmonics and the time-averaged
        modes); a stable result gives the category ``""``.
    generators
        ``(label, harmonic, kind)`` with kind ``"mesh"`` or ``"body"``
        (:func:`generator_table` for a model).
    omega
        The base frequency ``w1`` [rad/s].
    rotating_damping
        The system has rotating damping (names a time-invariant instability).
    """
    lam0 = result.averaged
    w = omega
    if result.stable:
        return Mechanism("")
    lead = complex(result.exponents[0])
    tol = float(result.tolerances[0]) if result.tolerances.size else 0.0
    atol = result.averaged_tol if result.averaged_tol.size == lam0.size else np.full(lam0.size, tol)
    if lam0.size and bool(np.any(lam0.real > atol)):
        cat = ROTATING_DAMPING if rotating_damping else CIRCULATORY
        return Mechanism(cat, "time-invariant", (), "", lead)
    h, mode_a, mode_h = result.partner[0] if result.partner else (0, -1, -1)
    table = generators
    coef = _decompose(h, table)
    if coef is None:
        return Mechanism(UNIDENTIFIED, "", (), f"partner harmonic {h} (x {w:.4g} rad/s)", lead)
    used = np.flatnonzero(coef)
    names = tuple(table[i][0] for i in used)
    kinds = {table[i][2] for i in used}
    category = MESH if kinds == {"mesh"} else ASYMMETRY if kinds == {"body"} else COMBINED
    if used.size == 1:
        resonance = "principal" if abs(int(coef[used[0]])) == 1 else "secondary"
    else:
        resonance = "combination"
    exc = combination_text(coef[used] * int(np.sign(h)), [table[i][0] for i in used])
    freq = abs(h) * w
    j = int(mode_a)
    wj = abs(lam0[j].imag) if j >= 0 else abs(lead.imag)
    if mode_h >= 0 and j >= 0 and np.isclose(lam0[mode_h], np.conj(lam0[j]), rtol=1e-9):
        modes = f"2 x {wj:.5g} rad/s"
    elif mode_h >= 0:
        wk = abs(lam0[mode_h].imag)
        same_sign = np.sign(lam0[mode_h].imag) == np.sign(lam0[j].imag if j >= 0 else lead.imag)
        modes = f"|{wj:.5g} - {wk:.5g}| rad/s" if same_sign else f"{wj:.5g} + {wk:.5g} rad/s"
    else:
        modes = f"2 x {wj:.5g} rad/s"
    relation = f"{modes} ~ {exc} ({freq:.5g} rad/s)"
    return Mechanism(category, resonance, names, relation, lead)
