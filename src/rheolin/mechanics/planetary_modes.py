"""Lin & Parker's mode types of a planetary set: rotational, translational and planet modes.

For equally spaced, identical planets on isotropic supports (Lin & Parker, J. Vib. Acoust.
121(3) 1999) every mode of the set is one of three types: in a *rotational* mode the sun, ring
and carrier only rotate and every planet moves alike; in a *translational* mode they only
translate (a degenerate pair); in a *planet* mode they do not move at all (multiplicity
``N - 3``). A set inside a drive train keeps these types approximately; a mode is labelled by
where the kinetic energy the set holds lies (``M_0``'s diagonal weights each DOF's motion).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["KIND_SHARE", "PLANET_SHARE", "SetDofs", "planetary_mode_kinds"]

#: Below this share of the central members' kinetic energy, a motion counts as absent; a mode
#: whose set holds less than half its kinetic energy is not labelled.
KIND_SHARE = 0.05
#: A planet mode leaves the central members at rest (by the cyclic symmetry, exactly): below
#: this share of the set's kinetic energy in them; a rotational mode may move them little.
PLANET_SHARE = 1e-3


@dataclass(frozen=True)
class SetDofs:
    """The DOFs of a set: the sun's, ring's and carrier's translations across the axis and
    their rotations about it (one node each), and every DOF of the planets."""

    translations: np.ndarray
    rotations: np.ndarray
    planets: np.ndarray


def planetary_mode_kinds(
    shapes: np.ndarray, mass_diagonal: np.ndarray, dofs: SetDofs
) -> np.ndarray:
    """``"rotational"``, ``"translational"``, ``"planet"``, ``"coupled"`` (the set moves in
    both ways) or ``""`` (the mode lives mostly outside the set) per mode shape (columns).

    Examples
    --------
    Sun (x, y, phiz) and two planets' tangential DOFs, unit masses:

    >>> d = SetDofs(np.array([0, 1]), np.array([2]), np.array([3, 4]))
    >>> shapes = np.array([[0, 0, 1, 1, 1], [1, 1j, 0, 1, -1], [0, 0, 0, 1, -1.0]]).T
    >>> planetary_mode_kinds(shapes, np.ones(5), d).tolist()
    ['rotational', 'translational', 'planet']
    """
    q = np.asarray(shapes)
    m = np.asarray(mass_diagonal, dtype=float).reshape(-1, 1)
    energy = m * np.abs(q) ** 2
    total = energy.sum(axis=0)
    tr = energy[dofs.translations].sum(axis=0)
    rot = energy[dofs.rotations].sum(axis=0)
    pl = energy[dofs.planets].sum(axis=0)
    central = tr + rot
    out = np.full(q.shape[1], "", dtype=object)
    for j in range(q.shape[1]):
        if tr[j] + rot[j] + pl[j] < 0.5 * total[j]:
            continue
        if central[j] < PLANET_SHARE * (central[j] + pl[j]):
            out[j] = "planet"
        elif tr[j] < KIND_SHARE * central[j]:
            out[j] = "rotational"
        elif rot[j] < KIND_SHARE * central[j]:
            out[j] = "translational"
        else:
            out[j] = "coupled"
    return out
