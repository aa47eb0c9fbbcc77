"""The contribution of one element to the periodic system: a :class:`Term`, and the same
contribution as a polynomial in the base frequency ``w1``: a :class:`SpeedTerm`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["SpeedTerm", "Term"]

Series = dict[int, np.ndarray]
#: Power ``p`` of ``w1`` -> the Fourier series multiplying ``w1**p``.
Powers = dict[int, Series]


@dataclass
class Term:
    """Fourier coefficients of one element's matrices and loads on its global DOFs.

    Parameters
    ----------
    dofs
        Global DOF indices, length ``d``.
    M, D, K
        Maps harmonic index ``k`` (units of ``w1``) to a ``d x d`` coefficient; both signs
        present, ``X_{-k} = conj(X_k)``.
    f
        Maps harmonic index ``k`` to a load vector of length ``d``.

    Examples
    --------
    >>> import numpy as np
    >>> t = Term(np.array([0, 1]), K={0: np.eye(2)})
    >>> sorted(t.K), t.M
    ([0], {})
    """

    dofs: np.ndarray
    M: dict[int, np.ndarray] = field(default_factory=dict)
    D: dict[int, np.ndarray] = field(default_factory=dict)
    K: dict[int, np.ndarray] = field(default_factory=dict)
    f: dict[int, np.ndarray] = field(default_factory=dict)


def _evaluate(powers: Powers, w1: float) -> Series:
    out: Series = {}
    for p, series in sorted(powers.items()):
        scale = float(w1) ** p
        for k, v in series.items():
            x = scale * np.asarray(v) if p else np.asarray(v)
            out[k] = out[k] + x if k in out else x
    return {k: out[k] for k in sorted(out)}


@dataclass
class SpeedTerm:
    """A :class:`Term` whose coefficients are polynomials in ``w1``.

    ``X_k(w1) = sum_p w1**p X_k^(p)``: every element of a rotating body is exactly such a
    polynomial of degree <= 2 (gyroscopic and circulatory terms are linear in the speed,
    centripetal ones quadratic), and its harmonic indices ``k`` do not depend on the speed.
    Each of ``M, D, K, f`` maps the power ``p`` to a Fourier series ``{k: X_k^(p)}``.

    Examples
    --------
    >>> import numpy as np
    >>> t = SpeedTerm(np.array([0]), M={0: {0: np.eye(1)}}, D={1: {0: 2 * np.eye(1)}})
    >>> t.at(10.0).D
    {0: array([[20.]])}
    """

    dofs: np.ndarray
    M: Powers = field(default_factory=dict)
    D: Powers = field(default_factory=dict)
    K: Powers = field(default_factory=dict)
    f: Powers = field(default_factory=dict)

    @classmethod
    def constant(cls, term: Term) -> SpeedTerm:
        """A term that does not depend on the speed (power 0 only)."""

        def wrap(x: Series) -> Powers:
            return {0: x} if x else {}

        return cls(term.dofs, wrap(term.M), wrap(term.D), wrap(term.K), wrap(term.f))

    def at(self, w1: float) -> Term:
        """The :class:`Term` at base frequency ``w1`` (sums of the powers, nothing dropped)."""
        return Term(
            self.dofs,
            _evaluate(self.M, w1),
            _evaluate(self.D, w1),
            _evaluate(self.K, w1),
            _evaluate(self.f, w1),
        )
