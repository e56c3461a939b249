"""Physical signals: unit-carrying signals, their math, and converters to and from causal
signals."""

__all__: list[str] = []
