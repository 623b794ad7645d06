"""Braking in a turn (open loop, after ISO 7975): the metrics against closed forms on exact
circles and spirals, the car settling on the circle the steady state predicts, the brake
balance moving the yaw response the way it must, the CLI, and named errors. The derivatives
through the run and the metrics are checked on the braking objectives, which compile the
same run once for all of them (tests/test_optimise_braking.py: forward mode against central
differences, reverse mode, the circle's steady state included, against forward mode)."""

import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from typer.testing import CliRunner

from jaxveh._core import GRAVITY, ParameterError
from jaxveh.cli import app
from jaxveh.manoeuvre import (
    brake_in_turn,
    brake_in_turn_metrics,
    circle_steer,
    simulate,
)
from jaxveh.vehicle import SpeedChange, load_car, with_params

SPEED, RADIUS = 80 / 3.6, 100.0


def _on_path(ts, speed, radius_of_t, turn=1.0, sideslip_deg=0.0):
    """Channels of a point driving along a path of curvature ``turn / radius_of_t(t)`` at
    ``speed(t)``, integrated finely (heading = course less the sideslip)."""
    fine = np.linspace(ts[0], ts[-1], 200_001)
    v = speed(fine)
    yaw_rate = turn * v / radius_of_t(fine)
    dt = np.diff(fine)
    course = np.concatenate([[0.0], np.cumsum(0.5 * (yaw_rate[1:] + yaw_rate[:-1]) * dt)])
    vx, vy = v * np.cos(course), v * np.sin(course)
    x = np.concatenate([[0.0], np.cumsum(0.5 * (vx[1:] + vx[:-1]) * dt)])
    y = np.concatenate([[0.0], np.cumsum(0.5 * (vy[1:] + vy[:-1]) * dt)])
    heading = np.degrees(course) - sideslip_deg
    return {
        "x": np.interp(ts, fine, x),
        "y": np.interp(ts, fine, y),
        "heading": (np.interp(ts, fine, heading) + 180.0) % 360.0 - 180.0,  # as the channel reads it
        "speed": np.interp(ts, fine, v),
        "yaw_rate": np.degrees(np.interp(ts, fine, yaw_rate)),
        "sideslip": np.full_like(ts, sideslip_deg),
        "ay": np.interp(ts, fine, v * yaw_rate) / GRAVITY,
    }


def _target(speed=SPEED, start=2.0):
    return SpeedChange(speed=speed, final_speed=0.5 * speed, rate=0.5 * GRAVITY, start=start, rise=0.2)


@pytest.mark.parametrize("turn", [1.0, -1.0])
def test_metrics_of_a_car_that_stays_on_its_circle_are_neutral(turn):
    """A car braking on exactly its initial circle (yaw rate v / R at every speed, a
    constant sideslip): yaw rate to the reference 1, no heading or path deviation, the yaw
    rate falling with the speed, the deceleration the speed's; the heading wraps past 180
    deg on the way and the metrics do not notice."""
    late = _target(start=37.0)
    ts = np.linspace(0.0, 40.0, 8001)  # more than a lap: the heading wraps
    ch = _on_path(ts, lambda t: np.asarray(jax.vmap(late)(jnp.asarray(t))), lambda t: RADIUS, turn,
                  sideslip_deg=-0.4 * turn)
    out = {k: float(v) for k, v in brake_in_turn_metrics(ts, ch, late).items()}
    assert out["initial_radius_m"] == pytest.approx(RADIUS, rel=1e-6)
    assert out["yaw_rate_ratio_to_reference"] == pytest.approx(1.0, abs=1e-6)
    assert out["heading_deviation_deg"] == pytest.approx(0.0, abs=1e-4)
    assert out["path_deviation_m"] == pytest.approx(0.0, abs=2e-4)
    assert out["sideslip_change_deg"] == pytest.approx(0.0, abs=1e-12)
    v0, v1 = float(late(37.0)), float(late(38.0))
    assert out["yaw_rate_ratio"] == pytest.approx(v1 / v0, rel=1e-6)
    assert out["deceleration_g"] == pytest.approx((v0 - v1) / GRAVITY, rel=1e-6)
    assert out["initial_ay_g"] == pytest.approx(turn * v0 ** 2 / RADIUS / GRAVITY, rel=1e-6)


def test_metrics_of_a_spiral_have_the_closed_form_deviations():
    """At constant speed on a spiral whose curvature grows linearly after t0
    (1/R = (1 + c s) / R0, s the time since t0): yaw rate ratio 1 + c t_n, heading deviation
    v c t_n^2 / (2 R0) rad into the turn, and the path inside the circle."""
    c, t0 = 0.05, 5.0
    ts = np.linspace(0.0, 7.0, 7001)
    ch = _on_path(ts, lambda t: np.full_like(t, SPEED), lambda t: RADIUS / (1.0 + c * np.maximum(t - t0, 0.0)))
    target = SpeedChange(speed=SPEED, final_speed=0.5 * SPEED, rate=5.0, start=t0, rise=0.2)
    out = {k: float(v) for k, v in brake_in_turn_metrics(ts, ch, target).items()}
    assert out["yaw_rate_ratio"] == pytest.approx(1.0 + c, rel=1e-6)
    assert out["yaw_rate_ratio_to_reference"] == pytest.approx(1.0 + c, rel=1e-6)
    assert out["heading_deviation_deg"] == pytest.approx(np.degrees(SPEED * c / (2.0 * RADIUS)), rel=1e-4)
    assert out["path_deviation_m"] < -0.01 and out["deceleration_g"] == pytest.approx(0.0, abs=1e-9)


@pytest.fixture(scope="module")
def car():
    return load_car(modes=0)


@pytest.fixture(scope="module")
def runs(car):
    """Left and right on the 100 m circle at 80 km/h, braking at 0.5 g from 3 s; the left
    again with the brakes balanced 50/50 (one compiled program for all)."""
    out = {}
    for name, right, share in (("left", False, 0.65), ("right", True, 0.65), ("left rear-biased", False, 0.5)):
        c = with_params(car, {"pid.brake_front_share": share})
        m = brake_in_turn(SPEED, float(circle_steer(car, SPEED, RADIUS, right=right)), 0.5)
        run = simulate(c, m)
        out[name] = (m, run, brake_in_turn_metrics(run.ts, run.channels, m.speed_target))
    return out


def test_the_car_settles_on_the_circle_the_steady_state_predicts(runs):
    for name in ("left", "right"):
        m, run, out = runs[name]
        assert run.stop_reason == "completed"
        assert float(out["initial_radius_m"]) == pytest.approx(RADIUS, rel=2e-3), name
        assert float(out["initial_ay_g"]) == pytest.approx((1.0 if name == "left" else -1.0) * SPEED ** 2 / RADIUS
                                                           / GRAVITY, rel=5e-3), name
        ts, yaw = np.asarray(run.ts), np.asarray(run.channels["yaw_rate"])
        before = np.interp([2.5, 3.0], ts, yaw)
        assert abs(before[1] - before[0]) < 1e-3 * abs(before[1])  # settled before the brakes


def test_braking_in_the_turn_follows_physics(runs):
    """Braking at 0.5 g: the yaw rate falls with the speed, but less than the speed does (the
    front axle, loaded by the transfer, gains grip: the car turns into the circle); more
    rear brake turns it in further; left and right are mirror images up to the tyres' small
    asymmetry."""
    left, right, rear = (runs[k][2] for k in ("left", "right", "left rear-biased"))
    assert 0.4 < float(left["deceleration_g"]) < 0.5
    assert float(left["yaw_rate_ratio"]) < 1.0 < float(left["yaw_rate_ratio_to_reference"])
    assert float(left["heading_deviation_deg"]) > 0.0 and float(left["path_deviation_m"]) < 0.0
    assert float(rear["yaw_rate_ratio_to_reference"]) > float(left["yaw_rate_ratio_to_reference"])
    assert float(rear["heading_deviation_deg"]) > float(left["heading_deviation_deg"])
    for key in ("yaw_rate_ratio", "yaw_rate_ratio_to_reference", "heading_deviation_deg", "path_deviation_m",
                "sideslip_change_deg", "deceleration_g"):
        assert float(right[key]) == pytest.approx(float(left[key]), rel=0.05, abs=1e-3), key


def test_cli_brake_in_turn_json(tmp_path):
    result = CliRunner().invoke(app, ["simulate", "brake-in-turn", "--rigid", "--json", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    out = json.loads(result.output)
    assert out["manoeuvre"] == "brake-in-turn" and out["stop_reason"] == "completed"
    assert out["initial_radius_m"] == pytest.approx(100.0, rel=2e-3) and out["steady_before_brake"]
    for key in ("steer_deg", "yaw_rate_ratio", "yaw_rate_ratio_to_reference", "heading_deviation_deg",
                "path_deviation_m", "sideslip_change_deg", "ay_g", "deceleration_g", "initial_ay_g", "after_s",
                "wall_time_s", "steps"):
        assert key in out
    assert (tmp_path / "brake_in_turn.png").stat().st_size > 0
    assert "yaw_rate_deg/s" in (tmp_path / "brake_in_turn.csv").read_text().splitlines()[0].split(",")


def test_cli_names_a_spin_instead_of_measuring_it():
    """Rear brakes locking at 2 g spin the car within the second the metrics need: the run
    stops on the event and the JSON says why there are no metrics."""
    result = CliRunner().invoke(app, ["simulate", "brake-in-turn", "--rigid", "--json", "--decel-g", "2",
                                      "--param", "pid.brake_front_share=0.2"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.output)
    assert out["stop_reason"].startswith("spin") and "no metrics" in out["metrics_error"]
    assert "heading_deviation_deg" not in out


@pytest.mark.parametrize("args, match", [
    (["--decel-g", "0"], "--decel-g"),
    (["--final-speed-kmh", "90"], "--final-speed-kmh"),
    (["--radius-m", "-5"], "--radius-m"),
    (["--steer-deg", "3", "--brake-start-s", "0.6"], "brake_start"),
])
def test_cli_refuses_bad_input(args, match):
    result = CliRunner().invoke(app, ["simulate", "brake-in-turn", *args, "--rigid", "--json"])
    assert result.exit_code != 0 and match in result.output


def test_bad_input_is_named(car):
    with pytest.raises(ParameterError, match="final_speed"):
        brake_in_turn(speed=20.0, final_speed=25.0)
    with pytest.raises(ParameterError, match="brake_start"):
        brake_in_turn(brake_start=0.6)
    with pytest.raises(ParameterError, match="radius"):
        circle_steer(car, SPEED, 0.0)
    with pytest.raises(ParameterError, match="after"):
        brake_in_turn_metrics(np.linspace(0.0, 5.0, 11), {}, _target(), after=0.0)
    with pytest.raises(ParameterError, match="brake onset"):
        brake_in_turn_metrics(np.linspace(0.0, 2.5, 11), {}, _target())
