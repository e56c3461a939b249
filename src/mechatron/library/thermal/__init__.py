"""Thermal domain: across = temperature T (K), through = heat flow Q (W)."""

__all__: list[str] = []
