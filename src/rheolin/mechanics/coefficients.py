"""One matrix of a model as polynomials in ``w1`` on fixed sparsity patterns: what
:class:`~rheolin.mechanics.template.SpeedTemplate` evaluates at every speed."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError

__all__ = ["POWERS", "PolynomialCoefficient"]

POWERS = 3  # w1^0, w1^1, w1^2


class PolynomialCoefficient:
    """``X_k(w1)`` for every harmonic ``k >= 0`` of one matrix, on fixed CSR patterns."""

    def __init__(self, name: str, n: int) -> None:
        self.name, self.n = name, n
        self._parts: dict[int, list[tuple[np.ndarray, np.ndarray, int, np.ndarray]]] = {}
        self.patterns: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def add(self, dofs: np.ndarray, powers: dict[int, dict[int, np.ndarray]]) -> None:
        d = dofs.size
        rows, cols = np.repeat(dofs, d), np.tile(dofs, d)
        for p, series in powers.items():
            if not 0 <= p < POWERS:
                raise ModelError(f"term `{self.name}`: power {p} of w1 is not in 0..2")
            for k, x in series.items():
                x = np.asarray(x)
                if x.shape != (d, d):
                    raise ModelError(
                        f"term `{self.name}[{k}]` must have shape ({d}, {d}), got {x.shape}"
                    )
                if k >= 0:
                    self._parts.setdefault(int(k), []).append((rows, cols, p, x.ravel()))

    def freeze(self) -> None:
        """Sum the parts into one CSR pattern per harmonic with a value row per power."""
        for k, parts in sorted(self._parts.items()):
            keys = np.concatenate([r * self.n + c for r, c, _, _ in parts])
            union, slot = np.unique(keys, return_inverse=True)
            values = np.zeros((POWERS, union.size), dtype=float if k == 0 else complex)
            start = 0
            for _, _, p, v in parts:
                stop = start + v.size
                np.add.at(values[p], slot[start:stop], v.real if k == 0 else v)
                start = stop
            rows, cols = union // self.n, union % self.n
            self.patterns[k] = (rows, cols, values)
        self._parts = {}

    def slots(self, dofs: np.ndarray) -> np.ndarray:
        """Positions of the ``dofs x dofs`` block (row-major) in harmonic 0's values."""
        rows, cols, _ = self.patterns[0]
        keys = (np.repeat(dofs, dofs.size) * self.n + np.tile(dofs, dofs.size)).astype(np.int64)
        return np.searchsorted(rows * self.n + cols, keys)

    def at(
        self, w1: float, extra: list[tuple[np.ndarray, np.ndarray]] | None = None
    ) -> dict[int, sp.csr_array]:
        """The coefficients ``{k: X_k}`` (``k >= 0``) at ``w1``, plus ``extra`` ``(slots,
        values)`` on harmonic 0 (speed-dependent joints); exact zeros dropped."""
        out: dict[int, sp.csr_array] = {}
        for k, (rows, cols, (x0, x1, x2)) in self.patterns.items():
            data = x0 + w1 * x1 + (w1 * w1) * x2
            if k == 0 and extra:
                for slot, vals in extra:
                    np.add.at(data, slot, vals)
            keep = data != 0
            if not keep.any():
                continue
            r, c, v = (rows, cols, data) if keep.all() else (rows[keep], cols[keep], data[keep])
            indptr = np.zeros(self.n + 1, dtype=np.int64)
            np.cumsum(np.bincount(r, minlength=self.n), out=indptr[1:])
            out[k] = sp.csr_array((v, c, indptr), shape=(self.n, self.n))
        return out
