"""Planar multibody mechanics: frames with position (x, y) and angle as across variables,
force (fx, fy) and torque as through variables."""

__all__: list[str] = []
