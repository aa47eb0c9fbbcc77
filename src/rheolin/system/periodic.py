"""The periodic system ``M(t) q'' + D(t) q' + K(t) q = f(t)`` as Fourier coefficients.

This is the one interface between mechanics and solvers (docs/conventions.md): every
coefficient is a Fourier series ``X(t) = sum_k X_k exp(i k w1 t)`` of a real signal, so
``X_{-k} = conj(X_k)``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, TypeVar

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError

__all__ = ["PeriodicSystem"]

Matrix = Any  # numpy.ndarray or scipy.sparse matrix/array
T = TypeVar("T")


def _is_sparse(x: object) -> bool:
    return sp.issparse(x)


def _sparse_data(x: Matrix) -> np.ndarray:
    """The stored values of a sparse matrix, duplicates summed (no copy when canonical)."""
    if getattr(x, "format", "") in ("csr", "csc") and x.has_canonical_format:
        return np.asarray(x.data)
    coo = x.tocoo()
    coo.sum_duplicates()
    return np.asarray(coo.data)


def _max_abs(x: Matrix) -> float:
    if _is_sparse(x):
        data = _sparse_data(x)
        return float(np.max(np.abs(data))) if data.size else 0.0
    return float(np.max(np.abs(x))) if np.size(x) else 0.0


def _conj(x: Matrix) -> Matrix:
    return x.conj() if _is_sparse(x) else np.conj(x)


def _same_pattern(a: Matrix, b: Matrix) -> bool:
    return (
        getattr(a, "format", "") == getattr(b, "format", "") in ("csr", "csc")
        and a.has_canonical_format
        and b.has_canonical_format
        and np.array_equal(a.indptr, b.indptr)
        and np.array_equal(a.indices, b.indices)
    )


def _close(a: Matrix, b: Matrix, scale: float) -> bool:
    if _is_sparse(a) and _is_sparse(b) and _same_pattern(a, b):
        diff = np.asarray(a.data) - np.asarray(b.data)  # no sparse subtraction needed
        return _max_abs(diff) <= (1e-12 * float(scale) if scale > 0 else 0.0)
    diff = a - b
    return _max_abs(diff) <= (1e-12 * float(scale) if scale > 0 else 0.0)


class PeriodicSystem:
    """Linear system with time-periodic coefficients.

    ``M(t) q'' + D(t) q' + K(t) q = f(t)`` with ``X(t) = sum_k X_k exp(i k omega t)``.

    Parameters
    ----------
    omega
        Base angular frequency ``w1`` [rad/s], > 0.
    M, D, K
        Maps from harmonic index ``k`` to the ``n x n`` coefficient ``X_k`` (NumPy array or
        SciPy sparse). Missing negative indices are filled as ``conj(X_k)``; ``X_0`` must be
        real. ``None`` means zero.
    f
        Map from harmonic index ``k`` to the load vector ``f_k`` of shape ``(n,)``.

    Examples
    --------
    A damped oscillator with a stiffness that varies as ``cos(w1 t)``:

    >>> import numpy as np
    >>> s = PeriodicSystem(omega=2.0, M={0: np.eye(1)}, D={0: 0.1 * np.eye(1)},
    ...                    K={0: np.eye(1), 1: 0.1 * np.eye(1)}, f={1: np.ones(1)})
    >>> s.n, s.time_invariant, s.coefficient_harmonics
    (1, False, [-1, 1])
    >>> s.load_harmonics
    [-1, 1]
    """

    omega: float
    n: int
    M: dict[int, Matrix]
    D: dict[int, Matrix]
    K: dict[int, Matrix]
    f: dict[int, np.ndarray]

    def __init__(
        self,
        omega: float,
        M: Mapping[int, Matrix] | None = None,
        D: Mapping[int, Matrix] | None = None,
        K: Mapping[int, Matrix] | None = None,
        f: Mapping[int, Any] | None = None,
        constraint: Any = None,
    ) -> None:
        try:
            w = float(omega)
        except (TypeError, ValueError):
            raise ModelError(f"`omega` must be a positive number [rad/s], got {omega!r}") from None
        if not np.isfinite(w) or w <= 0.0:
            raise ModelError(f"`omega` must be a positive finite number [rad/s], got {omega!r}")
        self.omega = w
        n = self._infer_size(M, D, K, f)
        self.n = n
        self.M = self._matrices("M", M, n)
        self.D = self._matrices("D", D, n)
        self.K = self._matrices("K", K, n)
        self.f = self._loads(f, n)
        if not (self.M or self.D or self.K):
            raise ModelError("the system is all zero: give at least one nonzero M, D or K")
        #: exact constraints between DOFs (rigid links; :class:`~rheolin.system.constraints.
        #: LinearConstraint`): every analysis eliminates them and answers on all DOFs
        self.constraint = constraint
        #: ``(ix, iy)``: DOF indices of the transverse planes ``(x, y)`` of every node (the
        #: spin about ``x cross y``), when known: gmres's whirl-pair preconditioner holds a
        #: rotating asymmetry exactly with them (:mod:`rheolin.solvers.krylov`)
        self.whirl_pairs: tuple[np.ndarray, np.ndarray] | None = None
        self._derived: dict[str, Any] = {}

    # ------------------------------------------------------------------ validation
    @staticmethod
    def _infer_size(*coeffs: Mapping[int, Any] | None) -> int:
        names = ("M", "D", "K", "f")
        for name, c in zip(names, coeffs, strict=True):
            if c is not None and not isinstance(c, Mapping):
                raise ModelError(
                    f"`{name}` must be a dict mapping harmonic index k to a "
                    f"{'vector' if name == 'f' else 'matrix'}, got {type(c).__name__}"
                )
        for c in coeffs:
            for v in (c or {}).values():
                shape = v.shape if _is_sparse(v) else np.shape(v)
                if len(shape) == 0:
                    return 1  # a scalar coefficient: a one-DOF system
                if shape[0] > 0:
                    return int(shape[0])
        raise ModelError("cannot infer the system size: give at least one of M, D, K")

    @staticmethod
    def _key(name: str, k: object) -> int:
        if isinstance(k, bool) or not isinstance(k, int | np.integer):
            raise ModelError(f"`{name}` keys must be integer harmonic indices, got {k!r}")
        return int(k)

    @classmethod
    def _matrices(cls, name: str, coeffs: Mapping[int, Matrix] | None, n: int) -> dict:
        out: dict[int, Matrix] = {}
        if coeffs is None:
            return out
        for k_raw, x in coeffs.items():
            k = cls._key(name, k_raw)
            where = f"`{name}[{k}]`"
            if _is_sparse(x):
                x = x if isinstance(x, sp.csr_array) else sp.csr_array(x)
                if not np.all(np.isfinite(x.data)):
                    raise ModelError(f"{where} contains NaN or inf")
            else:
                x = np.asarray(x)
                if x.dtype.kind not in "biufc":
                    raise ModelError(f"{where} must be numeric, got dtype {x.dtype}")
                if x.ndim == 0 and n == 1:
                    x = x.reshape(1, 1)
                if not np.all(np.isfinite(x)):
                    raise ModelError(f"{where} contains NaN or inf")
            if x.shape != (n, n):
                raise ModelError(f"{where} must have shape ({n}, {n}), got {x.shape}")
            if k == 0:
                if np.iscomplexobj(x):
                    if _max_abs(x.imag) > 1e-12 * max(_max_abs(x.real), 1e-300):
                        raise ModelError(
                            f"{where} must be real (the mean of a real signal); "
                            "it has an imaginary part"
                        )
                    x = x.real
                x = x.astype(float)
            else:
                x = x.astype(complex, copy=False) if _is_sparse(x) else x.astype(complex)
            out[k] = x
        cls._fill_conjugates(name, out)
        return {k: v for k, v in sorted(out.items()) if _max_abs(v) > 0.0}

    @staticmethod
    def _fill_conjugates(name: str, out: dict[int, Any]) -> None:
        for k in [k for k in out if k > 0]:
            xk = out[k]
            if -k in out:
                scale = max(_max_abs(xk), _max_abs(out[-k]))
                if not _close(out[-k], _conj(xk), scale):
                    raise ModelError(
                        f"`{name}[{-k}]` must equal conj(`{name}[{k}]`) for a real system "
                        f"(or be omitted and it is filled in)"
                    )
            else:
                out[-k] = _conj(xk)
        for k in [k for k in out if k < 0]:
            if -k not in out:
                out[-k] = _conj(out[k])

    @classmethod
    def _loads(cls, coeffs: Mapping[int, Any] | None, n: int) -> dict[int, np.ndarray]:
        out: dict[int, np.ndarray] = {}
        if coeffs is None:
            return out
        if not isinstance(coeffs, Mapping):
            raise ModelError(f"`f` must be a dict mapping k to a vector, got {type(coeffs)}")
        for k_raw, v in coeffs.items():
            k = cls._key("f", k_raw)
            where = f"`f[{k}]`"
            x = np.asarray(v.toarray() if _is_sparse(v) else v).reshape(-1)
            if x.dtype.kind not in "biufc":
                raise ModelError(f"{where} must be numeric, got dtype {x.dtype}")
            if x.shape != (n,):
                raise ModelError(f"{where} must have shape ({n},), got {np.shape(v)}")
            if not np.all(np.isfinite(x)):
                raise ModelError(f"{where} contains NaN or inf")
            if k == 0 and np.iscomplexobj(x):
                if np.max(np.abs(x.imag)) > 1e-12 * max(np.max(np.abs(x.real)), 1e-300):
                    raise ModelError(f"{where} must be real (the mean of a real signal)")
                x = x.real
            out[k] = x.astype(float if k == 0 else complex)
        cls._fill_conjugates("f", out)
        return {k: v for k, v in sorted(out.items()) if np.any(v != 0)}

    # ------------------------------------------------------------------ properties
    @property
    def coefficient_harmonics(self) -> list[int]:
        """Sorted nonzero harmonic indices present in any of M, D, K."""
        keys = set(self.M) | set(self.D) | set(self.K)
        return sorted(k for k in keys if k != 0)

    @property
    def load_harmonics(self) -> list[int]:
        """Sorted harmonic indices with a nonzero load."""
        return sorted(self.f)

    @property
    def time_invariant(self) -> bool:
        """True when M, D and K have no time-varying part."""
        return not self.coefficient_harmonics

    @property
    def is_sparse(self) -> bool:
        """True when any coefficient matrix is a SciPy sparse matrix."""
        return any(_is_sparse(x) for c in (self.M, self.D, self.K) for x in c.values())

    def coefficient(self, name: str, k: int) -> Matrix | None:
        """``X_k`` of ``name`` in {"M", "D", "K"}, or None when it is zero."""
        table = {"M": self.M, "D": self.D, "K": self.K}
        if name not in table:
            raise ValueError(f"`name` must be 'M', 'D' or 'K', got {name!r}")
        return table[name].get(int(k))

    def load(self, k: int) -> np.ndarray:
        """Load vector ``f_k`` (zeros when absent)."""
        v = self.f.get(int(k))
        return np.zeros(self.n, dtype=complex) if v is None else v.astype(complex)

    def evaluate(self, name: str, t: float) -> np.ndarray:
        """Dense real value of ``M(t)``, ``D(t)``, ``K(t)`` or ``f(t)`` at time ``t`` (small n)."""
        if name == "f":
            out_f = np.zeros(self.n)
            for k, v in self.f.items():
                out_f += (v * np.exp(1j * k * self.omega * t)).real
            return out_f
        table = {"M": self.M, "D": self.D, "K": self.K}
        if name not in table:
            raise ValueError(f"`name` must be 'M', 'D', 'K' or 'f', got {name!r}")
        out = np.zeros((self.n, self.n))
        for k, x in table[name].items():
            dense = x.toarray() if _is_sparse(x) else x
            out += (dense * np.exp(1j * k * self.omega * t)).real
        return out

    # ------------------------------------------------------------------ derived data
    def cached(self, key: str, build: Callable[[], T]) -> T:
        """The derived data ``key`` of this system, made by ``build()`` on the first request
        and kept on the system (its coefficients do not change once it is built).

        The coefficient blocks (:func:`rheolin.harmonics.blocks.coefficient_blocks`) are kept
        so, for the solve, the stability check and its memory estimate.

        >>> s = PeriodicSystem(1.0, K={0: np.eye(2)})
        >>> s.cached("trace", lambda: float(np.trace(s.K[0])))
        2.0
        >>> s.cached("trace", lambda: -1.0), s.kept("trace")
        (2.0, 2.0)
        """
        if key not in self._derived:
            self._derived[key] = build()
        return self._derived[key]

    def keep(self, key: str, value: Any) -> None:
        """Keep ``value`` as the derived data ``key``, replacing any (``None`` forgets it).

        For by-products of an analysis that a later one reuses: the harmonic-balance operator
        keeps the time-averaged modes of its ``modal`` inverse as ``"averaged_decomposition"``,
        and the lattice stability check starts from them (:mod:`rheolin.floquet.averaged`).

        >>> s = PeriodicSystem(1.0, K={0: np.eye(2)})
        >>> s.keep("note", "kept")
        >>> s.kept("note")
        'kept'
        >>> s.keep("note", None)
        >>> s.kept("note") is None
        True
        """
        if value is None:
            self._derived.pop(key, None)
        else:
            self._derived[key] = value

    def kept(self, key: str) -> Any:
        """The derived data ``key``, or ``None`` when none is kept."""
        return self._derived.get(key)

    def __repr__(self) -> str:
        return (
            f"PeriodicSystem(n={self.n}, omega={self.omega:.6g}, "
            f"coefficient_harmonics={self.coefficient_harmonics}, "
            f"load_harmonics={self.load_harmonics})"
        )
