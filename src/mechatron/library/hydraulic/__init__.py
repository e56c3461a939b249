"""Isothermal-liquid hydraulic domain: across = pressure p (Pa), through = volumetric flow
rate q (m^3/s)."""

__all__: list[str] = []
