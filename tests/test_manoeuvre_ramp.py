"""Ramp steer (Fig. 6.13, ISO 4138 continuous steer): the gradients of a slow ramp equal
those of the car's steady states at the same speed (root finding)."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from jaxveh._core import GRAVITY, ParameterError
from jaxveh.cli import app
from jaxveh.manoeuvre import Manoeuvre, RampSteer, ramp_steer_metrics, simulate, steady_state
from jaxveh.vehicle import load_car

# Fig. 6.13's speed, half the CLI's default rate (2 deg/s from 0.5 s; 0.065 g/s), its 2001
# points; 7 s reach about 0.4 g.
SPEED, RATE_DEG_S, DURATION, POINTS = 40.0 / 3.6, 2.0, 7.0, 2001


def _fake_channels(ay, ku_deg_per_g, wheelbase, speed=SPEED):
    """Channels of an ideal quasi-static ramp with a known understeer gradient."""
    r = ay * GRAVITY / speed  # rad/s
    delta = ku_deg_per_g * ay + np.rad2deg(wheelbase * r / speed)
    return {"ay": ay, "speed": np.full_like(ay, speed), "yaw_rate": np.rad2deg(r),
            "road_wheel_angle": np.stack([delta, delta, 0 * ay, 0 * ay], axis=1),
            "steering_wheel_angle": 5.0 * delta, "roll": 1.5 * ay, "sideslip": -0.8 * ay}


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_ramp_metrics_recover_a_known_gradient(side):
    ay = side * np.linspace(0.0, 0.6, 61)
    out = ramp_steer_metrics(_fake_channels(ay, 0.7, 1.6), wheelbase=1.6)
    assert out["understeer_gradient_deg_per_g"] == pytest.approx(0.7, rel=1e-9)
    assert out["roll_gradient_deg_per_g"] == pytest.approx(1.5, rel=1e-9)
    assert out["sideslip_gradient_deg_per_g"] == pytest.approx(-0.8, rel=1e-9)
    assert out["gradient_points"] == 21


@pytest.mark.parametrize("kwargs, match", [
    ({"wheelbase": 0.0}, "wheelbase = 0.0"),
    ({"wheelbase": 1.6, "ay_range_g": (0.3, 0.1)}, "ay_range_g"),
    ({"wheelbase": 1.6, "ay_range_g": (2.0, 3.0)}, "0 samples"),
])
def test_ramp_metrics_refuse_bad_input(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        ramp_steer_metrics(_fake_channels(np.linspace(0.0, 0.6, 61), 0.7, 1.6), **kwargs)


@pytest.fixture(scope="module")
def ramp():
    car = load_car(modes=0)
    law = RampSteer(rate=np.deg2rad(RATE_DEG_S), start=0.5, blend=0.1)
    run = simulate(car, Manoeuvre(steering=law, speed=SPEED, duration=DURATION), points=POINTS, rtol=1e-6)
    return car, run


def _steady_gradients(car, wheelbase):
    """The same least-squares gradients over steady states at the ramp's speed, 0.1-0.3 g."""
    states = [steady_state(car, speed=SPEED, ay=a * GRAVITY) for a in np.linspace(0.1, 0.3, 9)]
    channels = {k: np.stack([np.asarray(s.channels[k]) for s in states])
                for k in ("ay", "speed", "yaw_rate", "road_wheel_angle", "steering_wheel_angle", "roll", "sideslip")}
    return ramp_steer_metrics(channels, wheelbase)


@pytest.mark.slow
def test_slow_ramp_gradients_equal_the_steady_states(ramp):
    """The ramp (0.065 g/s) is quasi-static: its steering-wheel, roll and sideslip gradients
    equal the steady states' within 1 %; its understeer gradient, a small difference of two
    large angles on this near-neutral car, within 1 % of the Ackermann gradient l g / V^2.
    (At the CLI's 4 deg/s the sideslip gradient lags by 1.06 %: the ramp's own dynamics.)"""
    car, run = ramp
    assert run.stop_reason == "completed"
    wheelbase = float(car.params.vehicle.a + car.params.vehicle.b)
    got, want = ramp_steer_metrics(run.channels, wheelbase), _steady_gradients(car, wheelbase)
    for key in ("steering_wheel_gradient_deg_per_g", "roll_gradient_deg_per_g", "sideslip_gradient_deg_per_g"):
        np.testing.assert_allclose(got[key], want[key], rtol=0.01, err_msg=key)
    ackermann = np.rad2deg(wheelbase * GRAVITY / SPEED**2)
    key = "understeer_gradient_deg_per_g"
    assert abs(got[key] - want[key]) < 0.01 * ackermann, (got[key], want[key], ackermann)


@pytest.mark.slow
def test_cli_ramp_steer_reports_the_gradients(ramp):
    """The CLI's ramp (the fixture's compiled program serves) reports the API's gradients."""
    result = CliRunner().invoke(app, ["simulate", "ramp-steer", "--rigid", "--duration", str(DURATION),
                                      "--rate-deg-s", str(RATE_DEG_S), "--rtol", "1e-6", "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    car, run = ramp
    api = ramp_steer_metrics(run.channels, float(car.params.vehicle.a + car.params.vehicle.b))
    for key, value in api.items():
        np.testing.assert_allclose(out[key], value, rtol=1e-6, err_msg=key)
