"""The one failure of a per-harmonic inverse."""

from __future__ import annotations

__all__ = ["SingularBlockError"]


class SingularBlockError(RuntimeError):
    """``A0(n)`` could not be factorized (exactly singular: an undamped resonance)."""

    def __init__(self, n: int, detail: str) -> None:
        super().__init__(f"A0(n={n}) is singular ({detail})")
        self.n = n
        self.detail = detail
