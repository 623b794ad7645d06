"""The closed-loop driver: reference paths (closed forms), the pure-pursuit law (its exact
curvature on a circle, its gradient vs central differences), the lane-change metrics, and on
the rigid car the ISO 3888-1 lane change (lanes cleared, mirror symmetry) and the
closed-loop skid-pad (it settles on the car's own steady state by root finding)."""

import json
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from typer.testing import CliRunner

from jaxveh._core import ParameterError
from jaxveh.cli import app
from jaxveh.manoeuvre import (
    Circle,
    DoubleLaneChange,
    Manoeuvre,
    PurePursuit,
    car_width,
    constant_radius,
    constant_radius_metrics,
    lane_change,
    lane_change_metrics,
    simulate,
    steady_state,
    steering_ratio,
)
from jaxveh.tyre import mirror_symmetric
from jaxveh.vehicle import load_car

GAIN = 6.9  # rad m: a steering ratio of about 4 times a 1.7 m wheelbase


# ---- paths and the pure-pursuit law -------------------------------------------------------------

@pytest.mark.parametrize("turn", [1.0, -1.0])
def test_circle_target_is_on_the_circle_an_arc_ahead(turn):
    path = Circle(radius=50.0, turn=turn)
    target = np.asarray(path.target(jnp.zeros(2), 0.0, 10.0))
    angle = 10.0 / 50.0
    np.testing.assert_allclose(target, [50.0 * np.sin(angle), turn * 50.0 * (1.0 - np.cos(angle))], atol=1e-12)
    assert float(path.lateral_error(jnp.zeros(2))) == 0.0
    inside = jnp.array([0.0, turn * 1.0])  # 1 m towards the centre: the path's left in a left turn
    np.testing.assert_allclose(float(path.lateral_error(inside)), turn, rtol=1e-12)


@pytest.mark.parametrize("turn", [1.0, -1.0])
def test_pure_pursuit_on_the_circle_commands_its_curvature(turn):
    """On the circle and tangent to it, the pursuit circle is the path: kappa = turn / R
    exactly, wherever the car is on it."""
    radius = 40.0
    driver = PurePursuit(path=Circle(radius=radius, turn=turn), preview=12.0, gain=GAIN, lag=0.1)
    for theta in (0.0, 0.7, 2.5):  # the car's angle travelled round the circle
        position = jnp.array([radius * np.sin(theta), turn * radius * (1.0 - np.cos(theta))])
        heading = turn * theta
        np.testing.assert_allclose(float(driver.command(position, heading)), GAIN * turn / radius, rtol=1e-12)
        assert float(driver.rate(position, heading, GAIN * turn / radius)) == pytest.approx(0.0, abs=1e-12)


def test_pure_pursuit_on_a_straight_path():
    """Before the lane change the path is y = 0: a car offset by d steers back with
    kappa = -2 d / (L^2 + d^2) (the target L ahead on the line)."""
    driver = PurePursuit(path=DoubleLaneChange(entry=100.0, offset=3.5), preview=20.0, gain=GAIN, lag=0.1)
    assert float(driver.command(jnp.zeros(2), 0.0)) == 0.0
    d = 0.3
    np.testing.assert_allclose(float(driver.command(jnp.array([0.0, d]), 0.0)), GAIN * -2 * d / (400.0 + d * d),
                               rtol=1e-12)


def test_lane_change_path_is_smooth_and_follows_the_sections():
    path = DoubleLaneChange(entry=10.0, offset=3.5)
    x = np.array([0.0, 24.9, 55.0, 67.0, 80.0, 105.0, 200.0])
    np.testing.assert_allclose(np.asarray(path.centre(jnp.asarray(x))), [0, 0, 3.5, 3.5, 3.5, 0, 0], atol=1e-12)
    assert float(path.end) == 135.0
    # continuous curvature: first and second derivatives vanish at every section joint
    d1, d2 = jax.grad(path.centre), jax.grad(jax.grad(path.centre))
    for joint in (25.0, 55.0, 80.0, 105.0):
        for h in (-1e-9, 1e-9):
            assert abs(float(d1(joint + h))) < 1e-9 and abs(float(d2(joint + h))) < 1e-9
    np.testing.assert_allclose(float(d1(40.0)), 3.5 * 15.0 / 8.0 / 30.0, rtol=1e-12)  # smootherstep slope 15/8
    lanes = path.lanes(1.5)
    assert [w for *_, w in lanes] == pytest.approx([1.1 * 1.5 + 0.25, 1.2 * 1.5 + 0.25, 1.3 * 1.5 + 0.25,
                                                    1.3 * 1.5 + 0.25])
    assert [c for _, _, c, _ in lanes] == [0.0, 3.5, 0.0, 0.0]


def test_pure_pursuit_gradient_matches_central_differences():
    def command(params):
        preview, y, heading = params
        driver = PurePursuit(path=DoubleLaneChange(entry=10.0, offset=3.5), preview=preview, gain=GAIN, lag=0.1)
        return driver.command(jnp.stack([jnp.asarray(20.0), y]), heading)

    x = jnp.array([15.0, 0.4, 0.05])
    exact = np.asarray(jax.grad(command)(x))
    for k in range(3):
        h = 1e-6 * max(1.0, abs(float(x[k])))
        e = jnp.zeros(3).at[k].set(h)
        fd = (float(command(x + e)) - float(command(x - e))) / (2 * h)
        np.testing.assert_allclose(exact[k], fd, rtol=1e-6)


def test_bad_driver_input_is_named():
    with pytest.raises(ParameterError, match="Circle.turn"):
        Circle(radius=50.0, turn=0.5)
    with pytest.raises(ParameterError, match="Circle.radius"):
        Circle(radius=0.1, turn=1.0)
    with pytest.raises(ParameterError, match="PurePursuit.preview"):
        PurePursuit(path=Circle(radius=50.0, turn=1.0), preview=0.0, gain=GAIN, lag=0.1)
    with pytest.raises(ParameterError, match="PurePursuit.lag"):
        PurePursuit(path=Circle(radius=50.0, turn=1.0), preview=10.0, gain=GAIN, lag=0.0)
    with pytest.raises(ParameterError, match="car_width"):
        lane_change_metrics({}, DoubleLaneChange(entry=10.0, offset=3.5), 0.0)


def test_lane_change_metrics_on_a_made_up_run():
    """A car exactly on the path has the margin (w - b) / 2 in the narrowest lane; shifted
    0.2 m off it, 0.2 m less; a run that stops short names the lane it misses."""
    path, width = DoubleLaneChange(entry=10.0, offset=3.5), 1.5
    x = np.linspace(0.0, 140.0, 1401)
    run = {"x": x, "y": np.asarray(path.centre(jnp.asarray(x))), "steering_wheel_angle": np.zeros_like(x),
           "ay": np.zeros_like(x), "yaw_rate": np.zeros_like(x)}
    m = lane_change_metrics(run, path, width)
    assert m["max_path_error_m"] == 0.0 and m["lanes_cleared"]
    np.testing.assert_allclose(m["lane_margin_m"], 0.5 * (0.1 * width + 0.25))
    shifted = lane_change_metrics(run | {"y": run["y"] + 0.2}, path, width)
    np.testing.assert_allclose(shifted["lane_margin_m"], m["lane_margin_m"] - 0.2)
    assert not lane_change_metrics(run | {"y": run["y"] + 0.5}, path, width)["lanes_cleared"]
    short = {k: v[x < 60.0] for k, v in run.items()}
    with pytest.raises(ParameterError, match="x = 105"):
        lane_change_metrics(short, path, width)


# ---- on the rigid car ---------------------------------------------------------------------------

#: Save points of the closed-loop skid-pad: the CLI's default, so that its test reuses the program.
POINTS = 501


def _cli_points(manoeuvre):
    """The CLI's save points for a lane change (100 per second), so the fixture's program serves it."""
    return max(501, math.ceil(100.0 * float(manoeuvre.duration)) + 1)


@pytest.fixture(scope="module")
def car():
    return load_car(modes=0)


def test_steering_ratio_and_width_of_the_car(car):
    """The overall steering ratio (steering wheel per road wheel) of the shipped car is the
    ratio of the steady-state channels' steering-wheel and mean front road-wheel angles
    between gentle left and right turns at 5 m/s (1 %: roll steer and compliance at
    0.025 g); the width is the front track plus the tyres' section width."""
    ratio = steering_ratio(car)
    assert 3.0 < ratio < 6.0
    turns = [steady_state(car, speed=5.0, yaw_rate=r).channels for r in (0.05, -0.05)]  # R = 100 m, 0.025 g
    d_wheel = np.mean(np.asarray(turns[0]["road_wheel_angle"][:2]) - np.asarray(turns[1]["road_wheel_angle"][:2]))
    d_steer = float(turns[0]["steering_wheel_angle"]) - float(turns[1]["steering_wheel_angle"])
    np.testing.assert_allclose(d_steer / d_wheel, ratio, rtol=1e-2)
    tyre_width = float(np.max(np.asarray(car.params.tyres.width)))
    assert car_width(car) == pytest.approx(1.26 + tyre_width)


@pytest.fixture(scope="module")
def lane_changes(car):
    """The lane change at 80 km/h on the shipped car, and left and right on mirror-symmetric
    tyres at rtol 1e-10 (one compiled program: the offset and tolerance are traced)."""
    mirror = eqx.tree_at(lambda c: c.params.tyres, car, mirror_symmetric(car.params.tyres))
    points = _cli_points(lane_change(car))
    return {
        "shipped": simulate(car, lane_change(car), points=points),
        "left": simulate(mirror, lane_change(mirror, offset=3.5), points=points, rtol=1e-10),
        "right": simulate(mirror, lane_change(mirror, offset=-3.5), points=points, rtol=1e-10),
    }


@pytest.mark.slow
def test_lane_change_clears_the_iso_lanes(car, lane_changes):
    run = lane_changes["shipped"]
    assert run.stop_reason == "completed"
    ch = {k: np.asarray(v) for k, v in run.channels.items()}
    m = lane_change_metrics(ch, lane_change(car).steering.path, car_width(car))
    assert m["lanes_cleared"], m
    assert m["max_path_error_m"] < 1.0
    assert 0.3 < m["max_ay_g"] < 1.0  # a real manoeuvre, within the grip
    assert abs(ch["y"][-1]) < 0.05 and abs(ch["heading"][-1]) < 0.5  # back on the line
    assert np.max(np.abs(ch["speed"] - 80.0 / 3.6)) < 0.05
    assert float(np.max(ch["constraint_residual"])) < 1e-9


#: Channels that change sign in the mirror image (see tests/test_manoeuvre.py).
ODD = ("steering_wheel_angle", "y", "heading", "ay", "yaw_rate", "sideslip", "roll", "fy", "slip_angle", "camber",
       "road_wheel_angle")


@pytest.mark.slow
def test_lane_change_to_the_right_mirrors_the_left(lane_changes):
    """The closed loop keeps the mirror symmetry: at rtol 1e-10 every channel agrees with
    the mirror image to 1e-7 of its range (measured: 1.1e-8 on ax, the smallest channel,
    below 5e-9 on the rest; the two runs' step sequences differ by rounding)."""
    left, right = lane_changes["left"].channels, lane_changes["right"].channels
    for name, value in right.items():
        if name in ("modes", "constraint_residual"):
            continue  # no modes; the links' round-off
        value, mirrored = np.asarray(value), np.asarray(left[name]) * (-1.0 if name in ODD else 1.0)
        if mirrored.ndim == 2:
            mirrored = mirrored[:, [1, 0, 3, 2]]
        assert np.max(np.abs(value - mirrored)) <= 1e-7 * np.max(np.abs(value)), name


@pytest.mark.slow
def test_closed_loop_skid_pad_settles_on_the_steady_state(car):
    """30 s on the 50 m circle at 15 m/s (0.46 g): the steering settles, the car runs within
    0.5 m of the circle, and its steering-wheel angle, roll and sideslip equal the car's
    steady state by root finding at the same speed and turn rate to 1e-6 relative (measured:
    6e-9 on sideslip, below 5e-10 on the rest; rtol 1e-8, as at 1e-4 the integration's own
    scatter in the yaw rate is 2e-4)."""
    m = constant_radius(car, radius=50.0, speed=15.0, duration=30.0)
    run = simulate(car, m, points=POINTS, rtol=1e-8)
    assert run.stop_reason == "completed"
    got = constant_radius_metrics(run.ts, run.channels, m.steering.path)
    assert got["steering_wheel_range_deg"] < 1e-3
    assert abs(got["path_offset_m"]) < 0.5
    # the turn rate about the vertical from the heading (the yaw_rate channel is about the
    # rolled chassis's z axis: cos(roll) smaller)
    tail = np.asarray(run.ts) >= 25.0
    turn_rate = np.polyfit(np.asarray(run.ts)[tail], np.unwrap(np.radians(np.asarray(run.channels["heading"])[tail])),
                           1)[0]
    ss = steady_state(car, speed=15.0, yaw_rate=turn_rate)
    # a run's steering-wheel angle counts from straight running's (the tyres' ply steer needs some)
    straight = np.degrees(float(-steady_state(car, speed=15.0, yaw_rate=0.0).rack / car.params.rack_ratio))
    np.testing.assert_allclose(float(run.channels["steering_wheel_angle"][-1]) + straight,
                               float(ss.channels["steering_wheel_angle"]), rtol=1e-6)
    for name in ("roll", "sideslip", "ay", "yaw_rate"):
        np.testing.assert_allclose(float(run.channels[name][-1]), float(ss.channels[name]), rtol=1e-6, err_msg=name)


def test_simulate_refuses_an_unknown_steering(car):
    with pytest.raises(ParameterError, match="manoeuvre.steering"):
        simulate(car, Manoeuvre(steering=Circle(radius=50.0, turn=1.0), speed=10.0, duration=1.0))


@pytest.mark.slow
def test_cli_lane_change_json(tmp_path, lane_changes):
    """The fixture's compiled program serves the CLI (same car, driver and save points)."""
    result = CliRunner().invoke(app, ["simulate", "lane-change", "--rigid", "--json", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)
    for key in ("lanes_cleared", "lane_margin_m", "max_path_error_m", "car_width_m", "wall_time_s", "steps"):
        assert key in report
    assert report["lanes_cleared"] is True
    assert (tmp_path / "lane_change.png").exists() and (tmp_path / "lane_change.nc").exists()


@pytest.mark.slow
def test_cli_skid_pad_time_run_json():
    """``skid-pad --time-run``: the closed-loop run's settled values (the skid-pad test's
    compiled program serves: same car, driver and save points), in a few hundred steps: 222
    measured with the car's position and heading kept out of the IMEX split's implicit part,
    648 when they were in it (docs/manoeuvre.md, "Speed")."""
    result = CliRunner().invoke(app, ["simulate", "skid-pad", "--time-run", "--rigid", "--speed-kmh", "45",
                                      "--duration", "20", "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)
    assert report["manoeuvre"] == "skid-pad-time-run" and report["stop_reason"] == "completed"
    v = 45.0 / 3.6
    np.testing.assert_allclose(report["ay_g"], v * v / report["path_radius_m"] / 9.80665, rtol=2e-3)
    assert abs(report["path_radius_m"] - 50.0) < 0.5 and report["steering_wheel_range_deg"] < 1e-2
    assert report["steps"] < 400
    bad = CliRunner().invoke(app, ["simulate", "skid-pad", "--time-run", "--rigid", "--radius", "0.5"])
    assert bad.exit_code != 0 and "Circle.radius" in bad.output


@pytest.mark.slow
def test_library_form_runs_the_same_driver(car, lane_changes):
    """The first 2.5 s of the lane change (into the first transition) in the library form
    equal the fast form's on every channel to 1e-5 of its range at rtol 1e-8, as the
    open-loop runs do (tests/test_manoeuvre.py): the driver reads the chassis pose from either form's
    coordinates."""
    m = lane_change(car, duration=2.5)
    points = _cli_points(lane_change(car))  # the fixture's fast program serves
    fast = simulate(car, m, points=points, rtol=1e-8)
    lib = simulate(car, m, points=points, form="library", rtol=1e-8)
    assert lib.stop_reason == "completed"
    assert np.max(np.abs(np.asarray(lib.channels["steering_wheel_angle"]))) > 1.0  # the driver steers
    for name, value in lib.channels.items():
        if name in ("modes", "constraint_residual"):
            continue
        value = np.asarray(value)
        assert np.max(np.abs(np.asarray(fast.channels[name]) - value)) <= 1e-5 * np.max(np.abs(value)), name
