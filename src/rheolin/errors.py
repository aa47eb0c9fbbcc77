"""Exceptions raised by rheolin."""

from __future__ import annotations

__all__ = ["ModelError"]


class ModelError(ValueError):
    """Invalid model or system input; the message names the field and what is allowed."""
