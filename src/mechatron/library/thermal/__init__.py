"""Thermal domain: across = temperature T (K), through = heat flow Q (W).

Two-port components have ports ``A`` and ``B``: ``dT = A.T - B.T`` and ``Q`` is the heat
flow into the component at ``A`` (and out at ``B``). One-port components (heat capacitor,
sources, reference) have a single port ``port``.
"""

from mechatron.library.thermal.interfaces import HeatPort, TwoPort

__all__ = ["HeatPort", "TwoPort"]
