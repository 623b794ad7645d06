"""Straight-line acceleration and braking: the speed target's closed form, the brake balance
as data, the deceleration the brakes reach, the axle load transfer against the whole car's
moment balance, rear-wheel drive, the CLI, and named errors."""

import json

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from typer.testing import CliRunner

from jaxveh._core import GRAVITY, ParameterError
from jaxveh.cli import app
from jaxveh.manoeuvre import (
    Manoeuvre,
    StepSteer,
    accelerate,
    brake,
    manoeuvre_channels,
    save_times,
    simulate,
    start_trim,
    straight_line_metrics,
)
from jaxveh.vehicle import (
    SpeedChange,
    SpeedPID,
    aero_map_from_coefficients,
    load_car,
    total_mass,
    with_params,
)

SPEEDS = (8.0, 12.0, 16.0)  # m/s: in the settled hold of both braking runs of the load-transfer test


def test_speed_change_is_a_continuous_ramp_with_the_given_rate():
    target = SpeedChange(speed=25.0, final_speed=5.0, rate=8.0, start=0.5, rise=0.2)
    t1 = 0.5 + 20.0 / 8.0  # end of the hold
    ts = jnp.linspace(0.0, t1 + 1.0, 4001)
    v = np.asarray(jax.vmap(target)(ts))
    a = np.asarray(jax.vmap(target.acceleration)(ts))
    assert v[0] == 25.0 and v[-1] == pytest.approx(5.0, abs=1e-12)
    # the acceleration: 0, a linear rise over 0.2 s, -8 m/s^2 held, a linear fall
    expected = -8.0 * np.clip((ts - 0.5) / 0.2, 0.0, 1.0) + 8.0 * np.clip((ts - t1) / 0.2, 0.0, 1.0)
    np.testing.assert_allclose(a, expected, atol=1e-12)
    # the speed is the acceleration's integral (trapezoid rule on the fine grid)
    integral = 25.0 + np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * np.diff(np.asarray(ts)))])
    np.testing.assert_allclose(v, integral, atol=1e-4)
    assert target.kinks() == (0.5, 0.7, t1, t1 + 0.2)


@pytest.fixture(scope="module")
def car():
    return load_car(modes=0)


@pytest.fixture(scope="module")
def braking(car):
    """Braking from 100 to 20 km/h at 1 g and at 0.5 g (one program for both)."""
    return {g: simulate(car, brake(deceleration=g)) for g in (1.0, 0.5)}


def _channels(run):
    return {k: np.asarray(v) for k, v in run.channels.items()}


def test_braking_reaches_the_target_and_splits_the_torque_by_the_brake_balance(car, braking):
    m = brake(deceleration=1.0)
    run = braking[1.0]
    assert run.stop_reason == "completed"
    ch = _channels(run)
    out = straight_line_metrics(run.ts, ch, m.speed_target)
    assert out["ax_mean_g"] == pytest.approx(-1.0, abs=0.02)  # the PI loop's residual: drag, rolling resistance
    # within 1 % of the change 1 s after it (the PI loop's integral still sheds the drag it held)
    assert ch["speed"][-1] == pytest.approx(20.0 / 3.6, abs=0.01 * 80.0 / 3.6)
    torque = ch["wheel_torque"]
    braked = torque.sum(axis=1) < -1.0
    assert braked.sum() > 100
    share = torque[braked, :2].sum(axis=1) / torque[braked].sum(axis=1)
    np.testing.assert_allclose(share, float(car.params.pid.brake_front_share), rtol=1e-12)
    np.testing.assert_allclose(torque[braked, 0], torque[braked, 1], rtol=1e-12)  # equal sides
    assert out["front_torque_share"] == pytest.approx(0.65, rel=1e-12)
    assert out["pitch_mean_deg"] > 0.5 and out["pitch_gradient_deg_per_g"] < 0.0  # the nose dives
    # straight ahead: the tyres' small asymmetric offsets only
    assert np.max(np.abs(ch["yaw_rate"])) < 0.1
    np.testing.assert_allclose(ch["fz"][:, 0], ch["fz"][:, 1], rtol=5e-3)


def test_a_deceleration_beyond_the_car_is_flagged(car, braking):
    """3 g is beyond the tyres and the brake torque limit: the run completes, the car brakes
    as hard as it can, and the metrics say the target was not followed."""
    m = brake(deceleration=3.0)
    run = simulate(car, m)
    assert run.stop_reason == "completed"
    out = straight_line_metrics(run.ts, _channels(run), m.speed_target)
    assert not out["target_followed"] and -2.0 < out["ax_mean_g"] < -0.5
    followed = braking[1.0]
    assert straight_line_metrics(followed.ts, _channels(followed), brake(deceleration=1.0).speed_target)[
        "target_followed"]


def test_the_brake_balance_is_car_data(car):
    balanced = with_params(car, {"pid.brake_front_share": 0.5})
    ch = _channels(simulate(balanced, brake(deceleration=1.0)))
    torque = ch["wheel_torque"]
    braked = torque.sum(axis=1) < -1.0
    np.testing.assert_allclose(torque[braked, :2].sum(axis=1) / torque[braked].sum(axis=1), 0.5, rtol=1e-12)


def test_axle_load_transfer_equals_the_whole_car_moment_balance(car):
    """Without aero loads (which lower the car with the speed squared), at equal speed the
    front axle's load in two braking runs differs by ``-(m h + sum(I_w) / R) (ax_1 - ax_2) /
    l``: the moment balance of the whole car about the ground below its c.g. with no pitch
    acceleration, the wheels' spin deceleration ``ax / R`` included (about 4 % of it). The
    closed form takes the design c.g. height and lever arms; the dive moves them (about 1 %
    here, measured 1.1-1.5 % over these speeds)."""
    bare = eqx.tree_at(lambda c: c.params.aero, car, aero_map_from_coefficients(0.0, 0.0, 0.5))
    v = car.params.vehicle
    inertia = 2.0 * (v.unsprung_front.wheel_spin_inertia + v.unsprung_rear.wheel_spin_inertia)
    radius = float(jnp.mean(car.params.tyres.unloaded_radius))
    lever = (float(total_mass(v)) * float(v.h_cg) + float(inertia) / radius) / float(v.a + v.b)
    front, ax = {}, {}
    for g in (1.0, 0.5):
        run = simulate(bare, brake(deceleration=g))
        ch = _channels(run)
        held = np.asarray(run.ts) < 0.5 + (100.0 - 20.0) / 3.6 / (g * GRAVITY)  # before the ramp's end
        order = np.argsort(ch["speed"][held])
        speed = ch["speed"][held][order]
        front[g] = np.interp(SPEEDS, speed, ch["fz"][held][order, :2].sum(axis=1))
        ax[g] = np.interp(SPEEDS, speed, ch["ax"][held][order]) * GRAVITY
    expected = -lever * (ax[1.0] - ax[0.5])
    np.testing.assert_allclose(front[1.0] - front[0.5], expected, rtol=0.02)
    # the wheels' spin inertia matters at this tolerance
    assert np.all(np.abs(front[1.0] - front[0.5] + float(total_mass(v) * v.h_cg) / float(v.a + v.b)
                         * (ax[1.0] - ax[0.5])) > 0.03 * np.abs(expected))


def test_acceleration_drives_the_rear_wheels_through_the_open_differential(car):
    m = accelerate()
    run = simulate(car, m)
    ch = _channels(run)
    torque = ch["wheel_torque"]
    assert np.all(torque[:, :2] == 0.0)
    np.testing.assert_allclose(torque[:, 2], torque[:, 3], rtol=1e-12)
    out = straight_line_metrics(run.ts, ch, m.speed_target)
    assert out["ax_mean_g"] == pytest.approx(0.6, abs=0.012)
    assert out["front_torque_share"] == 0.0
    assert out["pitch_mean_deg"] < 0.0 and out["pitch_gradient_deg_per_g"] < 0.0  # the nose rises: squat
    assert out["time_to_final_speed_s"] == pytest.approx((90.0 - 30.0) / 3.6 / (0.6 * GRAVITY) + 0.2, rel=0.1)


@pytest.mark.slow
def test_dive_gradient_equals_central_differences(car):
    """Reverse mode through a braking run (the brakes' split, the target's feedforward):
    the mean pitch over the hold w.r.t. the brake balance and the target deceleration."""
    m = brake(deceleration=1.0, duration=2.0)
    ts = save_times(m, 101)
    trim = start_trim(car, m.speed)
    tol = jnp.asarray(1e-8, jnp.float64)

    @jax.jit
    def dive(x):
        c = eqx.tree_at(lambda c: c.params.pid.brake_front_share, car, x[0])
        mm = eqx.tree_at(lambda m: m.speed_target.rate, m, x[1])
        ch, _, _ = manoeuvre_channels(c, mm, ts, form="fast", trim=trim, solver="kencarp5", rtol=tol, atol=tol)
        return jnp.mean(ch["pitch"][60:])

    x = jnp.asarray([0.65, GRAVITY])
    grad = np.asarray(jax.jit(jax.grad(dive))(x))
    for k, h in enumerate((1e-3, 1e-2)):
        e = jnp.zeros(2).at[k].set(h)
        central = (float(dive(x + e)) - float(dive(x - e))) / (2 * h)
        assert grad[k] == pytest.approx(central, rel=2e-4), k
    assert abs(grad[0]) > 1e-3 and abs(grad[1]) > 1e-3  # both matter


def test_cli_brake_json(tmp_path):
    result = CliRunner().invoke(app, ["simulate", "brake", "--rigid", "--json", "--speed-kmh", "80",
                                      "--final-speed-kmh", "30", "--decel-g", "0.8", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    out = json.loads(result.output)
    assert out["manoeuvre"] == "brake" and out["stop_reason"] == "completed"
    assert out["ax_target_g"] == pytest.approx(-0.8, rel=1e-12)
    assert out["ax_mean_g"] == pytest.approx(-0.8, abs=0.02)
    ideal = ((80 / 3.6) ** 2 - (30 / 3.6) ** 2) / (2 * 0.8 * GRAVITY)  # m, at a constant 0.8 g
    assert ideal < out["distance_m"] < 1.25 * ideal
    for key in ("time_to_final_speed_s", "peak_ax_g", "pitch_gradient_deg_per_g", "front_load_share",
                "front_torque_share", "wall_time_s", "steps"):
        assert key in out
    assert (tmp_path / "brake.png").stat().st_size > 0
    header = (tmp_path / "brake.csv").read_text().splitlines()[0].split(",")
    assert "wheel_torque_fl_Nm" in header and "speed_m/s" in header


@pytest.mark.parametrize("args, match", [
    (["brake", "--decel-g", "-1"], "--decel-g"),
    (["accelerate", "--final-speed-kmh", "0"], "--final-speed-kmh"),
    (["brake", "--final-speed-kmh", "120"], "final_speed"),
])
def test_cli_refuses_bad_input(args, match):
    result = CliRunner().invoke(app, ["simulate", *args, "--rigid", "--json"])
    assert result.exit_code != 0 and match in result.output


def test_bad_input_is_named(car):
    with pytest.raises(ParameterError, match="pid.brake_front_share"):
        with_params(car, {"pid.brake_front_share": 1.5})
    with pytest.raises(ParameterError, match="SpeedChange.rate"):
        SpeedChange(speed=20.0, final_speed=10.0, rate=0.0)
    with pytest.raises(ParameterError, match="SpeedChange.final_speed"):
        SpeedChange(speed=20.0, final_speed=-1.0, rate=5.0)
    with pytest.raises(ParameterError, match="brake_front_share"):
        SpeedPID(kp=1.0, ki=1.0, brake_front_share=1.5)
    with pytest.raises(ParameterError, match="final_speed"):
        brake(speed=10.0, final_speed=20.0)
    with pytest.raises(ParameterError, match="final_speed"):
        accelerate(speed=20.0, final_speed=10.0)
    with pytest.raises(ParameterError, match="speed_target"):
        Manoeuvre(steering=StepSteer(amplitude=0.0, start=0.5, rise=0.2), speed=20.0, duration=3.0,
                  speed_target=SpeedChange(speed=25.0, final_speed=10.0, rate=5.0))
    with pytest.raises(ParameterError, match="hold"):
        m = brake(deceleration=1.0)
        straight_line_metrics(np.linspace(0.0, 4.0, 5), {}, m.speed_target)
