"""Blocks whose signal units are chosen per instance.

A physical-signal block's units are constructor keywords (``PSAdd(unit="N")``). Units of
declarations are class attributes in Mechatron, so the constructor returns an instance of
a subclass specialised to those units (cached: one subclass per class and unit set, with
the same name). The subclass is concrete and locally balanced like its base.
"""

from __future__ import annotations

import math

from mechatron.core import Component
from mechatron.errors import UnitError
from mechatron.units import check_unit, ureg

__all__ = ["UnitBlock", "unit_expr", "si_factor"]

_SPECIALISED: dict[tuple, type] = {}


def unit_expr(expr: str) -> str:
    """Canonical short spelling of a unit expression, ``"1"`` if dimensionless.

    ``unit_expr("(A)/(V)") == "A / V"``.
    """
    text = format(ureg.Unit(expr), "~")
    return text or "1"


def si_factor(unit: str, where: str) -> tuple[float, str]:
    """``(factor, si_unit)``: a value ``u`` in ``unit`` is ``factor * u`` in ``si_unit``.

    ``si_unit`` is ``unit`` itself when it is coherent SI (factor 1), else pint's base
    units. Offset units (degC, degF) are rejected: a signal is a value, not a point on a
    shifted scale.
    """
    check_unit(unit, where)
    zero = ureg.Quantity(0.0, unit).to_base_units().magnitude
    if zero != 0.0:
        raise UnitError(f"{where}: unit {unit!r} has an offset (a shifted scale); use an "
                        "absolute unit such as 'K' and subtract the offset with a "
                        "PSConstant and PSSubtract.", path=where)
    base = ureg.Quantity(1.0, unit).to_base_units()
    factor = float(base.magnitude)
    if math.isclose(factor, 1.0, rel_tol=0, abs_tol=1e-15):
        return 1.0, unit
    return factor, unit_expr(str(base.units))


class UnitBlock(Component, partial=True):
    """Base of blocks whose units are constructor keywords.

    A subclass lists its unit keywords with their defaults in ``unit_args`` and returns
    the unit-dependent declarations from the classmethod ``declare(**units)``.
    """

    unit_args: dict[str, str] = {}
    units: dict[str, str] = {}

    @classmethod
    def declare(cls, **units) -> dict:
        """Declarations (name -> Declaration) that depend on the units."""
        return {}

    def __new__(cls, *args, **kwargs):
        if cls.units and cls.__dict__.get("_specialised", False):
            return object.__new__(cls)
        units = {}
        for key, default in cls.unit_args.items():
            value = kwargs.get(key, default)
            if not isinstance(value, str):
                raise TypeError(f"{cls.__name__}({key}=...): a unit must be a string such "
                                f"as 'N*m', got {value!r}.")
            units[key] = check_unit(value, f"{cls.__name__}({key}=...)")
        key = (cls, tuple(sorted(units.items())))
        sub = _SPECIALISED.get(key)
        if sub is None:
            attrs = dict(cls.declare(**units))
            attrs.update(units=units, _specialised=True, __module__=cls.__module__,
                         __qualname__=cls.__qualname__, __doc__=cls.__doc__)
            sub = type(cls.__name__, (cls,), attrs)
            _SPECIALISED[key] = sub
        return object.__new__(sub)

    def __init__(self, **kwargs):
        for key in type(self).unit_args:
            kwargs.pop(key, None)
        super().__init__(**kwargs)
