"""Plots (matplotlib, PNG, no pyplot state, no window). Physics never imports this package.

>>> from rheolin.plots import point_plots, sweep_plot
"""

from .point import (
    plot_bearing_spectra,
    plot_convergence,
    plot_orbits,
    plot_spectrum,
    point_plots,
)
from .sweep import sweep_plot

__all__ = [
    "plot_bearing_spectra",
    "plot_convergence",
    "plot_orbits",
    "plot_spectrum",
    "point_plots",
    "sweep_plot",
]
