"""``python -m rheolin.cli``."""

from .app import main

main()
