"""Analysis of compiled models: linearization at an operating point and trimming."""

from mechatron.analysis.linear import OperatingPoint, linear_matrices, linearize, trim

__all__ = ["OperatingPoint", "linearize", "linear_matrices", "trim"]
