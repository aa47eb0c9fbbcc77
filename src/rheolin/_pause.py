"""Fault-injection pauses for the kill tests (never set in normal use).

A test that must land a signal inside a short window (the staging of a run's files, the
writing of a study's chunks) sets ``RHEOLIN_TEST_PAUSE_<POINT>`` to some seconds, so that
the window stays open whatever the machine's load.
"""

from __future__ import annotations

import os
import time

__all__ = ["pause"]


def pause(point: str) -> None:
    """Sleep ``RHEOLIN_TEST_PAUSE_<POINT>`` seconds when that variable is set.

    >>> pause("nowhere")  # unset: returns at once
    """
    value = os.environ.get(f"RHEOLIN_TEST_PAUSE_{point.upper()}")
    if value:
        time.sleep(float(value))
