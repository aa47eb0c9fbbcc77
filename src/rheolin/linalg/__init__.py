"""Per-harmonic linear algebra beneath the harmonic-balance operator: the time-averaged
pencil ``A0(n)``, the backends that invert it for every harmonic ``n >= 0`` (sparse or dense
LU, modal resolvent) and the one long-lived worker pool."""

from .backend import BACKENDS, BlockInverse, SingularBlockError, make_inverse
from .pencil import Pencil
from .pool import default_workers, map_chunks

__all__ = [
    "BACKENDS",
    "BlockInverse",
    "Pencil",
    "SingularBlockError",
    "default_workers",
    "make_inverse",
    "map_chunks",
]
