"""odomkit.units against the units' legal definitions (not against their own literals)."""
import math
from fractions import Fraction

from odomkit import units


def test_each_factor_is_its_definition():
    # International yard and pound agreement (1959): 1 yd = 0.9144 m; mile = 1760 yd, foot = yd/3.
    yard = Fraction(9144, 10000)
    assert units.MPH == float(1760 * yard / 3600)
    assert units.FOOT == float(yard / 3)
    assert units.KMH == float(Fraction(1000, 3600))
    assert math.isclose(360 * units.DEGREE, 2 * math.pi, rel_tol=1e-15)


def test_readers_and_check_use_the_same_factors():
    from odomkit.calibrate import check_ratios
    from odomkit.io.csvlog import UNIT_COLUMNS

    assert UNIT_COLUMNS["speed_mph"][1] == units.MPH and UNIT_COLUMNS["speed_kmh"][1] == units.KMH
    travel = dict((text, factor) for factor, text, _ in check_ratios._TRAVEL_UNITS)
    assert math.isclose(travel["a speed in mph read as m/s"], 1 / UNIT_COLUMNS["speed_mph"][1])
    mph, kmh = UNIT_COLUMNS["speed_mph"][1], UNIT_COLUMNS["speed_kmh"][1]
    assert math.isclose(travel["a speed in km/h read as mph"], mph / kmh)
