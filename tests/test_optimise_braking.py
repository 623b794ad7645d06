"""Braking objectives (optimise/_braking.py): their values against `simulate` and the
manoeuvre metrics on the same save times, their forward- and reverse-mode derivatives
against central differences, and named errors."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import optimise
from jaxveh import ParameterError
from jaxveh.manoeuvre import (
    brake,
    brake_in_turn,
    brake_in_turn_metrics,
    circle_steer,
    save_times,
    simulate,
    straight_line_metrics,
)
from jaxveh.vehicle import load_car
from optimise import objective_spec, objective_values
from optimise._braking import BRAKE_START, SAVES_PER_S

RTOL = 1e-8
NAMES = ("braking_deceleration", "braking_pitch_gradient", "braking_front_load_share", "brake_in_turn_yaw_ratio",
         "brake_in_turn_heading_deviation", "brake_in_turn_path_deviation")


@pytest.fixture(scope="module")
def car():
    return load_car(modes=0)


@pytest.fixture(scope="module")
def specs():
    return tuple(objective_spec(name, {"rtol": RTOL}) for name in NAMES)


@pytest.fixture(scope="module")
def values(car, specs):
    return eqx.filter_jit(objective_values)


def _points(duration):
    return int(round(SAVES_PER_S * duration)) + 1


def test_values_equal_the_manoeuvres_metrics(car, specs, values):
    """The objectives are the CLI's metrics of the same runs: straight-line braking from 100
    to 20 km/h at 1 g, and braking at 0.5 g on the design's own 100 m circle at 80 km/h
    (the steering from its steady state), both on the objectives' save times."""
    got = dict(zip(NAMES, np.asarray(values(car, specs))))
    m = brake()
    run = simulate(car, m, rtol=RTOL, points=_points(float(m.duration)))
    np.testing.assert_allclose(np.asarray(run.ts), save_times(m, _points(float(m.duration))))
    straight = straight_line_metrics(run.ts, run.channels, m.speed_target)
    assert got["braking_deceleration"] == pytest.approx(-straight["ax_mean_g"], rel=1e-6)
    assert got["braking_pitch_gradient"] == pytest.approx(straight["pitch_gradient_deg_per_g"], rel=1e-5)
    assert got["braking_front_load_share"] == pytest.approx(straight["front_load_share"], rel=1e-6)
    duration = BRAKE_START + 1.0 + 0.1
    m = brake_in_turn(80 / 3.6, float(circle_steer(car, 80 / 3.6, 100.0)), 0.5, duration=duration)
    run = simulate(car, m, rtol=RTOL, points=_points(duration))
    turn = {k: float(v) for k, v in brake_in_turn_metrics(run.ts, run.channels, m.speed_target).items()}
    assert turn["initial_radius_m"] == pytest.approx(100.0, rel=2e-3)
    assert got["brake_in_turn_yaw_ratio"] == pytest.approx(turn["yaw_rate_ratio_to_reference"], rel=1e-6)
    assert got["brake_in_turn_heading_deviation"] == pytest.approx(turn["heading_deviation_deg"], rel=1e-5)
    assert got["brake_in_turn_path_deviation"] == pytest.approx(turn["path_deviation_m"], rel=1e-5)
    # physics: the nose dives, the loaded front carries more than its static share, the car turns in
    assert got["braking_pitch_gradient"] < 0.0 and 0.5 < got["braking_front_load_share"] < 0.7
    assert got["brake_in_turn_yaw_ratio"] > 1.0 and got["brake_in_turn_heading_deviation"] > 0.0


def _with_share(car, share):
    return eqx.tree_at(lambda c: c.params.pid.brake_front_share, car, share)


@pytest.mark.slow
def test_forward_and_reverse_derivatives_equal_central_differences(car):
    """Along the brake balance: the heading deviation in the turn by forward mode (what
    study files use) and by reverse mode (``reverse=True``: the replayed run and the
    circle's steady state by the implicit function theorem), the dive per g by forward
    mode; each against a central difference of the same program."""
    turn = objective_spec("brake_in_turn_heading_deviation", {"rtol": RTOL})
    dive = objective_spec("braking_pitch_gradient", {"rtol": RTOL})

    @jax.jit
    def forward(share):
        return objective_values(_with_share(car, share), (turn, dive))

    x, h = jnp.asarray(0.65), 1e-3
    _, tangent = jax.jvp(forward, (x,), (jnp.ones_like(x),))
    central = (np.asarray(forward(x + h)) - np.asarray(forward(x - h))) / (2 * h)
    np.testing.assert_allclose(np.asarray(tangent), central, rtol=2e-3)
    assert float(tangent[0]) < 0.0  # more front brake: less turn-in

    def heading(share):
        return optimise.brake_in_turn_heading_deviation(_with_share(car, share), reverse=True, rtol=RTOL)

    grad = float(jax.jit(jax.grad(heading))(x))
    assert grad == pytest.approx(float(tangent[0]), rel=2e-3)


def test_bad_settings_are_named(car):
    with pytest.raises(ParameterError, match="decel_g"):
        optimise.braking_metrics(car, decel_g=0.0)
    with pytest.raises(ParameterError, match="final_speed_kmh"):
        optimise.braking_metrics(car, final_speed_kmh=120.0)
    with pytest.raises(ParameterError, match="radius_m"):
        optimise.brake_in_turn_objectives(car, radius_m=1.0)
    with pytest.raises(ParameterError, match="after_s"):
        optimise.brake_in_turn_objectives(car, after_s=0.0)
    with pytest.raises(ParameterError, match="no setting 'angle_deg'"):
        objective_spec("brake_in_turn_yaw_ratio", {"angle_deg": 3.0})
