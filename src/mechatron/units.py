"""Unit handling: user values with units converted to SI floats at build time.

Mechatron keeps runtime values as SI floats. Users may give a parameter as a number (taken
as SI), a string such as ``"340 uH"`` or ``"1500 rpm"``, or a pint quantity; the value is
converted to the declared unit of the parameter, and a value of the wrong dimension is an
error naming the parameter.

pint and its registry are loaded on first use (``import mechatron`` does not pay for them):
``ureg`` is a module attribute built by the first access.
"""

from __future__ import annotations

import functools
import numbers
import re

from mechatron.errors import UnitError

TYPE_CHECKING = False       # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:
    import pint

__all__ = ["ureg", "to_si", "to_base", "check_unit", "check_number_text", "dimensionality"]


@functools.lru_cache(maxsize=None)
def _registry() -> pint.UnitRegistry:
    import pint
    registry = pint.UnitRegistry()
    registry.define("@alias ohm = Ohm")  # the capitalised spelling engineers write
    return registry


def __getattr__(name: str):
    if name == "ureg":
        return _registry()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@functools.lru_cache(maxsize=None)
def _unit(unit: str) -> pint.Unit:
    return _registry().Unit(unit or "dimensionless")


def check_unit(unit: str, where: str = "") -> str:
    """Return ``unit`` if pint understands it; raise :class:`UnitError` otherwise."""
    try:
        _unit(unit)
    except Exception as exc:  # pint raises several types for bad unit strings
        raise UnitError(f"{where}: unknown unit {unit!r} ({exc}). "
                        "Use pint's notation, e.g. 'N*m/(rad/s)'.", path=where) from None
    return unit


_DIGIT_COMMA_DIGIT = re.compile(r"\d,\d")


def check_number_text(text: str, where: str) -> None:
    """Reject a comma between digits (``"7,1 ohm"``): pint would read it as 71 ohm.

    A decimal comma (German, French...) or a thousands separator is ambiguous; Mechatron
    accepts neither and asks for a decimal point."""
    if _DIGIT_COMMA_DIGIT.search(text):
        decimal = re.sub(r"(\d),(\d)", r"\1.\2", text)
        grouped = re.sub(r"(\d),(\d)", r"\1\2", text)
        raise UnitError(f"{where}: {text!r} has a comma in a number (a decimal comma or a "
                        f"thousands separator?); write a decimal point and no separator: "
                        f"{decimal!r} or {grouped!r}.", path=where)


def dimensionality(unit: str):
    """The pint dimensionality of a unit string (e.g. ``[length] / [time]``)."""
    return _unit(unit).dimensionality


def to_si(value, unit: str, where: str) -> float:
    """Convert a user value to a float in the SI base of ``unit``.

    Parameters
    ----------
    value : float, str or pint.Quantity
        A plain number is taken to be in ``unit`` already (Mechatron declares SI units), a
        string is parsed by pint (``"340 uH"``), a quantity is converted.
    unit : str
        The declared unit of the parameter, e.g. ``"H"``.
    where : str
        Who owns the value, used in messages, e.g. ``"motor.L"``.
    """
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, numbers.Real):
        return float(value)
    if isinstance(value, str):
        check_number_text(value, where)
        try:
            value = _registry().Quantity(value)
        except Exception:
            raise UnitError(f"{where}: cannot read {value!r} as a quantity. "
                            f"Write a number and a unit, e.g. '1.5 {unit or ''}'.".rstrip(),
                            path=where) from None
    import pint
    if isinstance(value, pint.Quantity):
        target = _unit(unit)
        if value.dimensionality != target.dimensionality:
            raise UnitError(
                f"{where}: expected a value in {unit or 'dimensionless'} "
                f"({_describe(target.dimensionality)}), got {value:~} "
                f"({_describe(value.dimensionality)}).", path=where)
        return float(value.to(target).magnitude)
    raise UnitError(f"{where}: expected a number or a quantity such as '1 {unit}', "
                    f"got {type(value).__name__} {value!r}.", path=where)


def to_base(text: str, where: str) -> float:
    """The magnitude of a quantity string in SI base units (``"340 uH"`` -> 3.4e-4), for
    comparing values whose target unit is not known yet (bounds in a problem file).

    Raises :class:`UnitError` for a comma in a number or text pint cannot read."""
    check_number_text(text, where)
    try:
        return float(_registry().Quantity(text).to_base_units().magnitude)
    except Exception:
        raise UnitError(f"{where}: cannot read {text!r} as a quantity; write a number and "
                        "a unit, e.g. '340 uH'.", path=where) from None


def _describe(dim) -> str:
    text = str(dim)
    return "dimensionless" if text in ("", "dimensionless") else text
