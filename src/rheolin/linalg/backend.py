"""Choice of the per-harmonic inverse of ``A0(n)``: sparse LU, batched dense LU or modal.

Every backend offers the same two operations over the harmonics ``n >= 0`` (rows):
``solve(R)`` (``A0(n)^-1 r_n``, zero rows skipped) and ``restricted(rows, cols)`` (the map
``z_n -> A0(n)^-1[rows, cols] z_n``, what GMRES on the support of the time variation applies
in every iteration). ``exact`` is False for the modal resolvent, whose error (checked below
``1e-11`` before use) the solvers remove by refinement against the recomputed residual.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Protocol

import numpy as np

from .errors import SingularBlockError
from .lu import BatchedLUInverse, LUInverse
from .modal import ModalInverse, ModalUnavailable
from .pencil import Pencil

__all__ = ["BACKENDS", "BlockInverse", "SingularBlockError", "choose_backend", "make_inverse"]

log = logging.getLogger(__name__)

#: Names accepted by ``solve(..., backend=...)``.
BACKENDS = ("auto", "lu", "dense", "modal")

#: Largest system for the batched dense LU, and its memory for all harmonics at once.
DENSE_MAX_DOF = 64
DENSE_MAX_BYTES = 256 * 2**20
#: Largest system for the modal resolvent (its eigendecomposition is dense, ``(2N)^3``).
MODAL_MAX_DOF = 1000
MODAL_MAX_BYTES = 512 * 2**20
#: Cost model of :func:`choose_backend`: seconds per ``(2N)^3`` of the dense eigendecomposition
#: and per SuperLU factor and solve of a small block (measured by bench/block_inverse.py).
EIG_SECONDS_PER_FLOP = 1.5e-9
LU_SECONDS_PER_BLOCK = 3e-4


class BlockInverse(Protocol):
    """``A0(n)^-1`` for every harmonic ``n >= 0`` of a harmonic-balance operator."""

    name: str
    exact: bool

    def solve(self, R: np.ndarray) -> np.ndarray: ...

    def restricted(
        self, rows: np.ndarray, cols: np.ndarray
    ) -> Callable[[np.ndarray], np.ndarray]: ...


def choose_backend(n_dof: int, n_harmonics: int) -> list[str]:
    """Backends to try, cheapest first, for ``n_harmonics`` blocks of size ``n_dof``.

    >>> choose_backend(126, 1473), choose_backend(42, 1), choose_backend(10000, 801)
    (['modal', 'lu'], ['dense'], ['lu'])
    """
    order = []
    eig = EIG_SECONDS_PER_FLOP * (2 * n_dof) ** 3
    if (
        n_dof <= MODAL_MAX_DOF
        and n_harmonics * 2 * n_dof * 16 <= MODAL_MAX_BYTES
        and eig < 0.25 * n_harmonics * LU_SECONDS_PER_BLOCK
    ):
        order.append("modal")
    if n_dof <= DENSE_MAX_DOF and n_harmonics * n_dof**2 * 16 <= DENSE_MAX_BYTES:
        order.append("dense")
    else:
        order.append("lu")
    return order


def make_inverse(
    pencil: Pencil,
    ns: np.ndarray,
    backend: str = "auto",
    workers: int = 1,
    sparse_backend: str = "auto",
    factor_budget: int | None = None,
) -> tuple[BlockInverse, str]:
    """The inverse of ``A0(n)`` for ``ns`` by ``backend``, and a note when it fell back.

    ``"modal"`` falls back to ``"lu"`` (and says so) when its accuracy check fails. Sparse
    ``"lu"`` factorizes with ``sparse_backend`` (:mod:`rheolin.linalg.direct`) and holds
    the factors within ``factor_budget`` bytes (None: all).
    Raises :class:`SingularBlockError` when a block is singular.
    """
    if backend not in BACKENDS:
        raise ValueError(f"`backend` must be one of {list(BACKENDS)}, got {backend!r}")
    order = choose_backend(pencil.n, len(ns)) if backend == "auto" else [backend]
    if order[-1] == "modal":
        order.append("lu")
    note = ""
    for name in order:
        try:
            if name == "modal":
                return ModalInverse(pencil, ns), note
            if name == "dense":
                return BatchedLUInverse(pencil, ns), note
            return LUInverse(pencil, ns, workers, sparse_backend, factor_budget), note
        except ModalUnavailable as exc:
            note = f"modal resolvent not used ({exc})"
            log.debug(note)
    raise AssertionError("unreachable: the LU backends always return")  # pragma: no cover
