"""Model files (TOML + pint units) and atomic file writes.

>>> from rheolin.io import load_model
"""

from .atomic import atomic_write
from .loader import LoadedModel, load_model, parse_document, parse_model, read_model

__all__ = [
    "LoadedModel",
    "atomic_write",
    "load_model",
    "parse_document",
    "parse_model",
    "read_model",
]
