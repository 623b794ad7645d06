"""Parameter paths (``jaxveh.params.get_at`` / ``set_at``) and ``jaxveh.vehicle.with_params``."""

import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh._core import ParameterError
from jaxveh.params import get_at, parse_path, set_all, set_at
from jaxveh.vehicle import load_car, with_params


@pytest.fixture(scope="module")
def car():
    return load_car(modes=6)


def test_paths_parse():
    assert parse_path("coupling") == (("coupling",), ())
    assert parse_path("chassis.stiffness_scale[2]") == (("chassis", "stiffness_scale"), (2,))
    assert parse_path(" vehicle.hard_points_front.points[4, -1] ") == (("vehicle", "hard_points_front", "points"),
                                                                        (4, -1))


def test_get_and_set_leaves_and_elements(car):
    p = car.params
    assert float(get_at(p, "arb_rates[0]")) == float(p.arb_rates[0])
    q = set_all(p, {"arb_rates[1]": 123.0, "chassis.stiffness_scale": 2.0,
                    "vehicle.hard_points_front.points[4, 2]": 0.1})
    np.testing.assert_array_equal(q.arb_rates, [p.arb_rates[0], 123.0])
    np.testing.assert_array_equal(q.chassis.stiffness_scale, np.full(6, 2.0))  # a scalar fills the leaf
    assert float(q.vehicle.hard_points_front.points[4, 2]) == 0.1
    np.testing.assert_array_equal(q.vehicle.hard_points_front.points[:4], p.vehicle.hard_points_front.points[:4])
    assert q.arb_rates.dtype == jnp.float64


@pytest.mark.parametrize("path, value, match", [
    ("arb_rate", 1.0, "CarParams has no field 'arb_rate'; known fields: aero, arb_rates"),
    ("arb_rates[2]", 1.0, r"indices \[2\] do not fit the shape \[2\]"),
    ("arb_rates[0, 0]", 1.0, "do not fit"),
    ("arb_rates[0", 1.0, "malformed"),
    ("vehicle.wheelbase", 1.6, "derived from other fields"),
    ("chassis.stiffness_scale", [1.0, 2.0], r"shape \[2\] does not fit \[6\]"),
    ("arb_rates[0]", [1.0, 2.0], "one element takes a scalar"),
])
def test_bad_paths_are_named(car, path, value, match):
    with pytest.raises(ParameterError, match=match):
        set_at(car.params, path, value)


def test_with_params_checks_the_result(car):
    changed = with_params(car, {"coupling": 0.5, "chassis.stiffness_scale[0]": 3.0})
    assert float(changed.params.coupling) == 0.5 and float(changed.params.chassis.stiffness_scale[0]) == 3.0
    assert changed.n_modes == car.n_modes and float(car.params.coupling) != 0.5  # a copy
    with pytest.raises(ParameterError, match="coupling must lie in"):
        with_params(car, {"coupling": 1.5})
    with pytest.raises(ParameterError, match="ModalBody.stiffness_scale"):
        with_params(car, {"chassis.stiffness_scale[3]": -1.0})
    with pytest.raises(ParameterError, match="arb_rates"):
        with_params(car, {"arb_rates[1]": -10.0})
