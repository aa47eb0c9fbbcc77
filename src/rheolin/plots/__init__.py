"""Plots (matplotlib, PNG, no pyplot state, no window). Physics never imports this package.

>>> from rheolin.plots import plot_campbell, plot_stability, point_plots, sweep_plot
"""

from .campbell import plot_campbell
from .point import (
    plot_bearing_spectra,
    plot_convergence,
    plot_orbits,
    plot_spectrum,
    point_plots,
)
from .stability import plot_stability
from .sweep import sweep_plot

__all__ = [
    "plot_bearing_spectra",
    "plot_campbell",
    "plot_convergence",
    "plot_orbits",
    "plot_spectrum",
    "plot_stability",
    "point_plots",
    "sweep_plot",
]
