"""diagnosis.units: conversions against the SI definitions (BIPM SI Brochure, 9th ed.;
NIST SP 811 Appendix B for psi and rpm)."""
import math

import numpy as np
import pytest

from diagnosis.errors import DiagnosisError, UnitError
from diagnosis.units import compatible, convert, parse_unit


@pytest.mark.parametrize("value, unit_from, unit_to, expected", [
    (2.5, "bar", "Pa", 2.5e5),                       # 1 bar = 1e5 Pa (SI Brochure Table 8)
    (350.0, "kPa", "Pa", 350e3),
    (0.6, "MPa", "bar", 6.0),
    (12.0, "mm", "m", 0.012),
    (3.0, "cm", "mm", 30.0),
    (90.0, "deg", "rad", math.pi / 2),              # 1 deg = pi/180 rad
    (180.0, "deg/s", "rad/s", math.pi),
    (1500.0, "N mm", "N m", 1.5),
    (2.0, "N*m", "Nm", 2.0),
    (0.3, "kN m", "N m", 300.0),
    (250.0, "mV", "V", 0.25),
    (20.0, "ms", "s", 0.02),
    (5.0, "g/s", "kg/s", 5e-3),
    (1.0, "psi", "Pa", 6894.757293168),             # NIST SP 811 B.8: 1 psi = 6.894 757 kPa
    (60.0, "rpm", "rad/s", 2 * math.pi),             # 1 rev/min = 2 pi / 60 rad/s
    (25.0, "degC", "K", 298.15),
    (1.0, "J/(kg K)", "m^2 s^-2 K^-1", 1.0),
    (3.0, "L/min", "m^3/s", 5e-5),
    (1.0, "µm", "m", 1e-6),
    (1013.25, "hPa", "atm", 1.0),                   # 1 atm = 101 325 Pa exactly
])
def test_conversion_factors(value, unit_from, unit_to, expected):
    assert float(convert(value, unit_from, unit_to)) == pytest.approx(expected, rel=1e-12)


def test_round_trip_and_shape():
    x = np.linspace(-3.0, 7.0, 11).reshape(11, 1)
    y = convert(x, "deg", "rad")
    assert y.shape == (11, 1)
    np.testing.assert_allclose(convert(y, "rad", "deg"), x, rtol=1e-14)
    same = convert(x, "N m", "N m")
    assert same is not x and np.array_equal(same, x)


def test_dimensions_are_tracked():
    assert parse_unit("N").dimension == parse_unit("kg m/s^2").dimension
    assert parse_unit("Pa").describe_dimension() == "kg m^-1 s^-2"
    assert compatible("N m s/rad", "kg m^2 s^-1 rad^-1")
    assert not compatible("rad", "m")   # angles are a dimension of their own


@pytest.mark.parametrize("unit_from, unit_to, words", [
    ("rad", "m", ["'rad'", "'m'", "incompatible"]),
    ("N", "N m", ["'N'", "'N m'", "incompatible"]),
    ("furlong", "m", ["'furlong'", "unknown symbol"]),
    ("m", "parsec", ["'parsec'", "unknown symbol"]),
    ("m//s", "m/s", ["more than one '/'"]),
    ("degC m", "K", ["degC", "alone"]),
])
def test_bad_units_name_both(unit_from, unit_to, words):
    with pytest.raises(UnitError) as info:
        convert(1.0, unit_from, unit_to)
    message = str(info.value)
    for word in words + [repr(unit_from), repr(unit_to)]:
        assert word in message
    assert info.value.unit_from == unit_from and info.value.unit_to == unit_to
    assert isinstance(info.value, DiagnosisError) and isinstance(info.value, ValueError)
