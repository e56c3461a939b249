"""Magnetic domain: across = magnetomotive force (A), through = magnetic flux (Wb)."""

__all__: list[str] = []
