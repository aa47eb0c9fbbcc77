"""Choosing one representative per exponent among the copies a lattice search finds."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["ACCEPT_WEIGHT", "CENTRED", "CLUSTER_TOL", "DEPENDENT", "LOCK_CAP", "LOCK_TOL"]


#: Averaged exponents closer than this (relative) are searched together.
CLUSTER_TOL = 1e-4


#: A Ritz vector counts for its target's search when its energy centroid is at most this
#: (0.5: split evenly between harmonic 0 and a neighbour, as in a principal resonance).
CENTRED = 0.5 + 1e-3


#: A target's search stops at a centred Ritz vector holding this share of its mode (of the
#: strongest mode's weight at harmonic 0): strongly mixed modes have no single owner.
ACCEPT_WEIGHT = 0.25


#: Eigenvectors of one value are dependent when the smallest singular value of the stacked
#: unit vectors is below this fraction of the largest.
DEPENDENT = 1e-3

#: A candidate whose conjugate lies within this (relative) of one of its own copies may be
#: one of a locked pair: inside a parametric resonance the two exponents split apart with
#: ``Im = h w1 / 2`` exactly, and a truncation that leaves ``Im`` a little off makes the
#: decaying one look like a complex pair with its conjugate (on the gearbox variant at 3874
#: rpm, order 2: -16.84 +- 1043.16i, 0.024 off the lock, where the monodromy matrix has +6.07
#: and -16.82). Its conjugate is then not counted as another exponent: the search must find
#: the second one (the split partner, or the conjugate's copy when the pair has not split).
LOCK_TOL = 1e-4

#: ... at most this fraction of ``w1``.
LOCK_CAP = 0.01


@dataclass
class Candidate:
    """An eigenpair a lattice search found, with what the selection judges it by."""

    lam: complex
    y: np.ndarray  # balanced first-order right eigenvector over the lattice
    energy: np.ndarray  # energy fraction per lattice harmonic
    centroid: float
    edge: float
    top: tuple[int, int]  # the two most energetic harmonics (indices, not positions)
    dominant: int  # averaged mode with the largest weight at harmonic 0
    shift: int
    weights: np.ndarray  # modal weights at harmonic 0, largest = 1
    slack: float = 0.0  # rounding error of the dominant averaged exponent (x SAFETY)
    families: tuple[int, ...] = ()  # clusters it can stand for, most likely first
    forced: bool = False  # taken only to fill its cluster (see _fill)
    search: int = -1  # the cluster whose search found it
    home: int = -1  # the cluster it stands for
    #: ``(lam, q, u, P(lam)^H u, residual)`` when already polished (a tracked exponent)
    polished: tuple[Any, ...] | None = None
    #: a tracked exponent's move per move of its averaged exponent (NaN: not tracked)
    rate: complex = complex("nan")


def targets(lam0: np.ndarray, w: float, near: Any = None) -> np.ndarray:
    """The averaged exponents ``lam0`` a search targets, by increasing frequency: those in the
    upper half plane (real ones included; a conjugate is found with its upper twin), or the
    ones nearest the values ``near`` (one in the lower half plane replaced by its twin)."""
    scale0 = np.maximum(np.abs(lam0), w)
    upper = np.flatnonzero(lam0.imag >= -1e-9 * scale0)
    if near is not None:
        picks = {int(np.argmin(np.abs(lam0 - z))) for z in np.atleast_1d(near)}
        picks = {
            j
            if lam0[j].imag >= -1e-9 * scale0[j]
            else int(np.argmin(np.abs(lam0 - np.conj(lam0[j]))))
            for j in picks
        }
        upper = np.array(sorted(picks), dtype=int)
    return upper[np.argsort(lam0[upper].imag, kind="stable")]


def clusters(lam0: np.ndarray, targets: np.ndarray, w: float) -> list[np.ndarray]:
    """Targets grouped where averaged exponents (nearly) coincide (a double eigenvalue of an
    isotropic rotor): one search must find the exponents of the whole group."""
    out: list[np.ndarray] = []
    used = np.zeros(lam0.size, dtype=bool)
    for j in targets:
        if used[j]:
            continue
        near = targets[np.abs(lam0[targets] - lam0[j]) <= CLUSTER_TOL * max(abs(lam0[j]), w)]
        near = near[~used[near]]
        used[near] = True
        out.append(near)
    return out


def count(kept: list[tuple[Candidate, bool]]) -> int:
    return sum(2 if conj_too else 1 for _, conj_too in kept)


def select(
    pool: list[Candidate],
    quotas: dict[int, int],
    w: float,
    nh: int,
    share: Any = None,
) -> list[tuple[Candidate, bool]]:
    """Representatives, best centred first, each standing for one cluster of targets.

    A candidate is skipped when it is a copy of an accounted exponent (``lambda + i h w1``
    with ``h`` the shift between their most energetic harmonics), when it has the same value
    as accounted ones and its eigenvector lies in their span (the same exponent found again;
    a multiple exponent has independent eigenvectors and counts once per dimension), or
    when every cluster it can stand for is full (so a copy that escaped recognition cannot
    take the place of another mode's exponent). Returns ``(candidate,
    conjugate_is_another_exponent)`` pairs.
    """
    order = sorted(range(len(pool)), key=lambda i: (pool[i].centroid, pool[i].edge))
    left = dict(quotas)
    kept: list[tuple[Candidate, bool]] = []
    # (lambda, top harmonics, unit eigenvector, slack) of every accounted exponent
    known: list[tuple[complex, tuple[int, int], np.ndarray, float]] = []
    for i in order:
        if not any(v > 0 for v in left.values()):
            break
        c = pool[i]
        home = [f for f in c.families if left.get(f, 0) > 0]
        if not home:
            continue
        if any(_copy_of(c, lam, top, w, slack=sl) for lam, top, _, sl in known):
            continue
        same = [v for lam, _, v, sl in known if abs(c.lam - lam) <= _tol(c, lam, w) + sl]
        y = c.y / np.linalg.norm(c.y)
        if same:
            sv = np.linalg.svd(np.column_stack([*same, y]), compute_uv=False)
            if sv[-1] <= DEPENDENT * sv[0]:
                continue
        mirrored = (-c.top[0], -c.top[1])
        # at most a hundredth of w1: copies lie w1 apart, and a slack near w1 / 2 (a
        # hunting-tooth period) would take every exponent for one of a locked pair
        lock = min(LOCK_TOL * max(abs(c.lam), w), LOCK_CAP * w)
        selfconj = _copy_of(c, np.conj(c.lam), mirrored, w, allow_zero=True, slack=lock)
        kept.append((c, not selfconj))
        known.append((c.lam, c.top, y, c.slack))
        left[home[0]] -= 1
        c.home = home[0]
        if not selfconj:
            known.append((np.conj(c.lam), mirrored, _mirror(y, nh), c.slack))
            # the conjugate counts for the same cluster, or for another one with room
            spare = [f for f in home if left.get(f, 0) > 0]
            if spare:
                left[spare[0]] -= 1
    if share is not None:
        _fill(pool, left, kept, known, w, share)
    return kept


def _fill(
    pool: list[Candidate],
    left: dict[int, int],
    kept: list[tuple[Candidate, bool]],
    known: list[tuple[complex, tuple[int, int], np.ndarray, float]],
    w: float,
    share: Any,
) -> None:
    """Clusters still without their exponents (strongly mixed modes whose copies the copy
    test cannot tell apart at this truncation) take, from their own search, the candidate
    whose eigenvector carries most of the cluster's modes summed over all harmonics
    (``share(candidate, cluster)``), not the same eigenpair as an accounted one."""
    for cid, room in left.items():
        while room > 0:
            own = [
                c
                for c in pool
                if c.search == cid
                and not any(abs(c.lam - lam) <= _tol(c, lam, w) + sl for lam, _, _, sl in known)
            ]
            if not own:
                break
            best = max(own, key=lambda c: share(c, cid) / (1.0 + c.centroid))
            selfconj = _copy_of(
                best, np.conj(best.lam), (-best.top[0], -best.top[1]), w, allow_zero=True
            )
            kept.append((best, not selfconj))
            known.append((best.lam, best.top, best.y / np.linalg.norm(best.y), best.slack))
            if not selfconj:
                known.append((np.conj(best.lam), best.top, best.y, best.slack))
            best.forced = True
            best.home = cid
            room -= 1 if selfconj else 2
        left[cid] = room


def _mirror(y: np.ndarray, nh: int) -> np.ndarray:
    """The eigenvector of the conjugate exponent: ``conj(y_{-h})`` (the lattice is symmetric
    and sorted, so harmonic ``-h`` sits at the reversed position)."""
    return np.conj(y.reshape(2, nh, -1)[:, ::-1, :].ravel())


def _tol(c: Candidate, lam: complex, w: float) -> float:
    scale = max(abs(c.lam), abs(lam), w)
    return 1e-8 * scale + 1e-3 * np.sqrt(c.edge) * scale + c.slack


def _copy_of(
    c: Candidate,
    lam: complex,
    top: tuple[int, int],
    w: float,
    allow_zero: bool = False,
    slack: float = 0.0,
) -> bool:
    """True when ``c.lam = lam + i h w`` for a shift ``h`` between their energetic harmonics."""
    tol = _tol(c, lam, w) + slack
    for tk in top:
        for tc in c.top:
            h = tk - tc
            if h == 0 and not allow_zero:
                continue
            if abs(c.lam - lam - 1j * h * w) <= tol:
                return True
    return False
