"""The ``rheolin`` command line; the terminal belongs to this package only."""

from .app import app, main

__all__ = ["app", "main"]
