"""Results: compute an operating point, label it as an ``xarray.Dataset``, write files.

>>> from rheolin.results import point_dataset, complex_amplitude, complex_values
"""

from .api684 import Peak, amplification_factors
from .compute import OperatingPoint, harmonic_set, solve_point
from .dataset import (
    complex_amplitude,
    complex_values,
    point_dataset,
    stability_text,
    write_dataset,
)
from .summary import summarize, write_summary

__all__ = [
    "OperatingPoint",
    "Peak",
    "amplification_factors",
    "complex_amplitude",
    "complex_values",
    "harmonic_set",
    "point_dataset",
    "solve_point",
    "stability_text",
    "summarize",
    "write_dataset",
    "write_summary",
]
