"""Shared fixtures: small circuits and drives used across the test suite."""

import matplotlib

matplotlib.use("Agg")
