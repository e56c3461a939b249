"""Visualization of simulation results: animations and trajectory plots of planar
mechanisms (see :mod:`mechatron.viz.mechanism`)."""

from mechatron.viz.mechanism import (Mechanism, VisualizationError, animate,
                                     find_mechanism, plot_trajectories)

__all__ = ["animate", "plot_trajectories", "find_mechanism", "Mechanism",
           "VisualizationError"]
