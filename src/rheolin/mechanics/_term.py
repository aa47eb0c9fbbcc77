"""The contribution of one element to the periodic system: a :class:`Term`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Term"]


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
