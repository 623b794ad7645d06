"""Non-linear 4-DOF model: skid-pad root finding vs time integration, step steer, gradients."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import central_difference
from jax.test_util import check_grads

from jaxveh.analytic import (
    FLEXIBLE,
    GRAVITY,
    RIGID,
    VARIANTS,
    ConstantSteer,
    SmoothStep,
    simulate,
    skidpad_steady_state,
    skidpad_sweep,
    step_steer_metrics,
    understeer_gradient,
    understeer_gradient_rigid,
)
from jaxveh.analytic._model import PF, PHIF, PHIR, PR, R, V
from jaxveh.analytic._transient import Trajectory
from jaxveh.params import load_analytic_vehicle


@pytest.fixture(scope="module")
def vehicle():
    return load_analytic_vehicle()


@pytest.mark.slow
@pytest.mark.parametrize("name", ["rigid", "flexible"])
def test_root_finding_equals_end_of_long_integration(vehicle, name):
    variant = VARIANTS[name]
    radius = 50.0
    ss = skidpad_steady_state(vehicle, 0.8 * GRAVITY, variant, radius)
    traj = simulate(vehicle, ConstantSteer(ss.delta), variant, ss.speed, 30.0, n_save=2)
    end = traj.states[-1]
    # The integration starts straight at rest in yaw; after 30 s it has settled on the circle.
    assert float(end[V]) == pytest.approx(float(ss.v), abs=1e-7)
    assert float(end[R]) == pytest.approx(float(ss.yaw_rate), rel=1e-7)
    assert float(end[PHIF]) == pytest.approx(float(ss.phi_front), rel=1e-6)
    assert float(end[PHIR]) == pytest.approx(float(ss.phi_rear), rel=1e-6)
    assert float(traj.ay[-1]) == pytest.approx(0.8 * GRAVITY, rel=1e-6)
    assert abs(float(end[PF])) < 1e-8 and abs(float(end[PR])) < 1e-8


@pytest.mark.slow
def test_small_ay_slope_equals_linear_understeer_gradient(vehicle):
    # At small ay load transfer is second order: the slope of δ is ku of (3.11) / (3.16).
    ay = 0.01 * GRAVITY
    for variant, ku in ((RIGID, understeer_gradient_rigid), (VARIANTS["flexible_roll_steer"], understeer_gradient)):
        state, sens = skidpad_sweep(vehicle, jnp.asarray([ay]), variant)
        assert float(1.0 / sens[0]) == pytest.approx(float(ku(vehicle)), rel=2e-3)
        assert float(state.delta_dynamic[0] / ay) == pytest.approx(float(ku(vehicle)), rel=2e-3)


@pytest.mark.slow
def test_above_grip_limit_is_reported(vehicle):
    state, sens = skidpad_sweep(vehicle, jnp.asarray([0.5, 3.0]) * GRAVITY, FLEXIBLE)
    assert bool(state.converged[0]) and not bool(state.converged[1])
    assert np.isfinite(float(sens[0]))
    with pytest.raises(Exception, match="(?i)nonlinear solve|root|converge|failed"):
        skidpad_steady_state(vehicle, 3.0 * GRAVITY, FLEXIBLE, throw=True).delta.block_until_ready()


@pytest.mark.slow
def test_implicit_gradient_of_steer_angle(vehicle):
    def delta(x):
        v = eqx.tree_at(lambda veh: (veh.kC, veh.kF), vehicle, (x[0], x[1]))
        return skidpad_steady_state(v, 1.0 * GRAVITY, FLEXIBLE).delta

    x0 = np.array([float(vehicle.kC), float(vehicle.kF)])
    g = np.asarray(jax.grad(delta)(jnp.asarray(x0)))
    fd = central_difference(delta, x0, 1.0)
    np.testing.assert_allclose(g, fd, rtol=1e-5)


def test_check_grads_of_skidpad_trim(vehicle):
    """Implicit-function derivatives of the trim, forward and reverse mode, in ay (m/s^2) and
    kC (scaled by 1e4 Nm/rad so one finite-difference step suits both)."""

    def trim(x):
        v = eqx.tree_at(lambda veh: veh.kC, vehicle, 1e4 * x[1])
        state = skidpad_steady_state(v, x[0], FLEXIBLE)
        return jnp.stack([state.delta, state.phi_front - state.phi_rear])

    check_grads(jax.jit(trim), (jnp.asarray([6.0, 2.2]),), order=1, modes=("fwd", "rev"), eps=1e-4, rtol=1e-5)


@pytest.mark.slow
def test_sweep_sensitivity_equals_finite_difference_of_curve(vehicle):
    ays = jnp.asarray([1.0, 1.0 + 1e-4, 1.0 - 1e-4]) * GRAVITY
    state, sens = skidpad_sweep(vehicle, ays, FLEXIBLE)
    fd = float((ays[1] - ays[2]) / (state.delta[1] - state.delta[2]))
    assert float(sens[0]) == pytest.approx(fd, rel=1e-6)


def test_metrics_on_second_order_closed_form():
    # y = 1 - exp(-ζωt)(cos ωd t + ζ/sqrt(1-ζ²) sin ωd t): overshoot exp(-πζ/sqrt(1-ζ²)).
    zeta, wn = 0.3, 20.0
    wd = wn * np.sqrt(1 - zeta**2)
    ts = np.linspace(0, 3, 30001)
    y = 1 - np.exp(-zeta * wn * ts) * (np.cos(wd * ts) + zeta / np.sqrt(1 - zeta**2) * np.sin(wd * ts))
    states = np.zeros((len(ts), 9))
    states[:, R] = y
    states[:, PHIF] = y
    traj = Trajectory(ts=jnp.asarray(ts), states=jnp.asarray(states), steer=jnp.ones(len(ts)), ay=jnp.asarray(y))
    steer = SmoothStep(1.0, 0.0, 1e-9)
    m = step_steer_metrics(traj, steer)
    assert m["yaw_rate_overshoot_pct"] == pytest.approx(100 * np.exp(-np.pi * zeta / np.sqrt(1 - zeta**2)), rel=1e-4)
    assert m["yaw_rate_peak_time_s"] == pytest.approx(np.pi / wd, abs=2e-4)
    # 2 % envelope settling bound: exp(-ζωt)/sqrt(1-ζ²) = 0.02.
    assert m["twist_settling_time_s"] <= np.log(1 / (0.02 * np.sqrt(1 - zeta**2))) / (zeta * wn) + 1e-3


def test_step_steer_flexible_vs_rigid(vehicle):
    steer = SmoothStep(np.radians(1.5), 0.0, 0.1)
    rigid = step_steer_metrics(simulate(vehicle, steer, RIGID, 25.0, 4.0, n_save=2001), steer)
    flex = step_steer_metrics(simulate(vehicle, steer, FLEXIBLE, 25.0, 4.0, n_save=2001), steer)
    assert rigid["twist_settling_time_s"] is None
    assert flex["twist_settling_time_s"] > 0.3
    assert flex["yaw_rate_overshoot_pct"] > rigid["yaw_rate_overshoot_pct"]
    # Steady ay equals the constant-speed steady state of the same steer angle.
    assert flex["ay_steady_g"] == pytest.approx(rigid["ay_steady_g"], rel=0.02)


@pytest.mark.slow
def test_gradient_through_time_integration(vehicle):
    steer = SmoothStep(np.radians(1.5), 0.0, 0.1)

    def yaw_rate_at_half_second(kc):
        v = eqx.tree_at(lambda veh: veh.kC, vehicle, kc)
        return simulate(v, steer, FLEXIBLE, 25.0, 0.5, n_save=2).states[-1, R]

    kc = float(vehicle.kC)
    g = float(jax.grad(yaw_rate_at_half_second)(jnp.asarray(kc)))
    fd = central_difference(lambda x: yaw_rate_at_half_second(x[0]), np.array([kc]), 50.0)[0]
    assert g == pytest.approx(fd, rel=1e-4)


