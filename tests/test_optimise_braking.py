"""Braking objectives (optimise/_braking.py): their values against `simulate` and the
manoeuvre metrics on the same save times, their forward-mode derivatives against central
differences, reverse mode against forward mode, and named errors. One compiled forward-mode
program serves the values and the differences (a plain forward program, a forward-mode one
and a reverse-mode one took 11 of CI's 50 minutes)."""

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


#: Step in the brake balance of the central differences (the objectives are smooth in it).
SHARE_STEP = 1e-3


@pytest.fixture(scope="module")
def with_tangent(car, specs):
    """One compiled program for the module: the six objectives and their forward-mode
    derivatives (what study files use) along the brake balance, at a given balance."""

    @jax.jit
    def program(share):
        return jax.jvp(lambda s: objective_values(_with_share(car, s), specs), (share,), (jnp.ones_like(share),))

    return program


@pytest.fixture(scope="module")
def at_design(car, with_tangent):
    """Values and derivatives at the car's own brake balance, and the values a step
    :data:`SHARE_STEP` either side (all in one test's time: the suite may drop the compiled
    program between tests, conftest.py)."""
    x = car.params.pid.brake_front_share
    values, tangent = with_tangent(x)
    plus, minus = (np.asarray(with_tangent(x + s * SHARE_STEP)[0]) for s in (1.0, -1.0))
    central = (plus - minus) / (2 * SHARE_STEP)
    return tuple(dict(zip(NAMES, np.asarray(a))) for a in (values, tangent, central))


def _points(duration):
    return int(round(SAVES_PER_S * duration)) + 1


def _with_share(car, share):
    return eqx.tree_at(lambda c: c.params.pid.brake_front_share, car, share)


def test_values_equal_the_manoeuvres_metrics(car, at_design):
    """The objectives are the CLI's metrics of the same runs: straight-line braking from 100
    to 20 km/h at 1 g, and braking at 0.5 g on the design's own 100 m circle at 80 km/h
    (the steering from its steady state), both on the objectives' save times."""
    got = at_design[0]
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


def test_forward_derivatives_equal_central_differences(at_design):
    """Every objective's forward-mode derivative along the brake balance against a central
    difference of the same program; more front brake turns the car in less."""
    _, tangent, central = at_design
    for name in NAMES:
        assert tangent[name] == pytest.approx(central[name], rel=2e-3, abs=1e-6), name
    assert tangent["brake_in_turn_heading_deviation"] < 0.0


@pytest.mark.slow
def test_reverse_derivative_equals_forward(car, at_design):
    """Reverse mode (``reverse=True``: the replayed run and the circle's steady state by the
    implicit function theorem) gives the forward-mode derivative of the heading deviation."""

    def heading(share):
        return optimise.brake_in_turn_heading_deviation(_with_share(car, share), reverse=True, rtol=RTOL)

    grad = float(jax.jit(jax.grad(heading))(car.params.pid.brake_front_share))
    assert grad == pytest.approx(at_design[1]["brake_in_turn_heading_deviation"], rel=1e-6)


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
