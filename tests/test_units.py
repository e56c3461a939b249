"""Tests of user values with units, `mechatron.units`."""

from __future__ import annotations

import pytest

from mechatron.errors import UnitError
from mechatron.units import to_base, to_si


def test_quantities_convert_to_si():
    assert to_si("340 uH", "H", "m.L") == pytest.approx(340e-6)
    assert to_si("7.1 ohm", "Ohm", "m.R") == pytest.approx(7.1)
    assert to_si("1500 rpm", "rad/s", "m.w") == pytest.approx(1500 * 2 * 3.141592653589793
                                                              / 60)


@pytest.mark.parametrize("text, decimal, grouped", [("7,1 ohm", "7.1 ohm", "71 ohm"),
                                                    ("7,1", "7.1", "71"),
                                                    ("1,000 uH", "1.000 uH", "1000 uH")])
def test_a_comma_in_a_number_is_rejected_not_read_as_digits(text, decimal, grouped):
    # pint alone reads "7,1 ohm" as 71 ohm: ten times the value meant
    with pytest.raises(UnitError) as info:
        to_si(text, "Ohm" if "ohm" in text else ("H" if "H" in text else ""), "motor.R")
    msg = str(info.value)
    assert msg.startswith(f"motor.R: {text!r} has a comma in a number")
    assert repr(decimal) in msg and repr(grouped) in msg
    assert info.value.path == "motor.R"


def test_to_base_compares_quantities_before_their_target_unit_is_known():
    assert to_base("340 uH", "f.L") == pytest.approx(340e-6)
    assert to_base("2 mH", "f.L") > to_base("1500 uH", "f.L")
    with pytest.raises(UnitError, match="f.L: cannot read 'lots' as a quantity"):
        to_base("lots", "f.L")
    with pytest.raises(UnitError, match="comma"):
        to_base("1,5 mH", "f.L")
