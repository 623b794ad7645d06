"""Steady states of the fast car by root finding: straight running, steady cornering and the
skid-pad curve (issue 12 item 3), checked against force balances and central differences
of the solves (against the end of a long time integration in tests/test_manoeuvre.py,
which has the time integration compiled)."""


import json

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from typer.testing import CliRunner

from jaxveh._core import GRAVITY, ParameterError
from jaxveh.cli import app
from jaxveh.manoeuvre import CONDITIONS, skid_pad, steady_state
from jaxveh.manoeuvre._steady import compiled_core, condition_kinds
from jaxveh.multibody import rotation_matrix
from jaxveh.vehicle import SetupError, load_car, static_corner_loads, with_params

RADIUS = 50.0
#: 0.11 ... 0.59 g at speeds half-way between the aero table's knots (1 m/s apart, piecewise
#: linear: a central difference across a knot would see its kink)
AY = np.asarray([7.5, 9.5, 11.5, 12.5, 14.5, 16.5]) ** 2 / RADIUS


@pytest.fixture(scope="module")
def car():
    return load_car(modes=6)


@pytest.fixture(scope="module")
def pad(car):
    return skid_pad(car, RADIUS, AY)


def _vertical_load(car, state):
    """Weight plus the aero loads' vertical share (N): drag along the chassis x axis and
    downforce along its -z axis, at the forward speed the powertrain holds."""
    mass = float(jnp.sum(static_corner_loads(car.params.vehicle))) / GRAVITY
    drag, front, rear = car.params.aero.loads(state.speed_target)
    a = rotation_matrix("zyx", state.state.q[3:6])
    return mass * GRAVITY + float(drag * a[2, 0] + (front + rear) * a[2, 2])


def test_skid_pad_points_are_steady_turns(car, pad):
    """Every point converged on the 50 m circle at its lateral acceleration; no residual rate;
    the links close; the tyres carry the weight and the downforce; turning left."""
    s = pad.states
    assert np.all(np.asarray(pad.ok))
    assert float(jnp.max(s.residual)) < 1e-8
    np.testing.assert_allclose(s.radius, RADIUS, rtol=1e-10)
    np.testing.assert_allclose(s.ay, AY, rtol=1e-10)
    assert float(jnp.max(s.channels["constraint_residual"])) < 1e-10
    ch = s.channels
    # the chassis-axis ay channel differs from the horizontal one by the roll and sideslip
    np.testing.assert_allclose(ch["ay"], AY / GRAVITY, rtol=2e-3)
    assert np.all(np.asarray(ch["yaw_rate"]) > 0.0) and np.all(np.diff(np.asarray(ch["roll"])) > 0.0)
    # the chassis-axis yaw rate: the turn's rate sqrt(ay / R) tilted by roll and pitch
    np.testing.assert_allclose(np.radians(ch["yaw_rate"]), np.sqrt(AY / RADIUS), rtol=1e-3)
    for k in range(len(AY)):
        state = jax.tree.map(lambda x, k=k: x[k], s)
        np.testing.assert_allclose(float(jnp.sum(state.channels["fz"])), _vertical_load(car, state), rtol=1e-6)
    # load transfer to the outside (right) wheels
    fz = np.asarray(ch["fz"])
    assert np.all(fz[:, 1] > fz[:, 0]) and np.all(fz[:, 3] > fz[:, 2])


def test_skid_pad_gradients_equal_central_differences(car, pad):
    """The exact d channel / d ay (implicit function theorem) against central differences of
    two more curves, every channel (a step of 0.01 m/s^2: the solves' own noise, ~1e-10,
    stays far below the differences)."""
    h = 1e-2
    plus, minus = skid_pad(car, RADIUS, AY + h), skid_pad(car, RADIUS, AY - h)
    for name, exact in pad.gradients.items():
        if name == "constraint_residual":
            continue
        fd = (np.asarray(plus.states.channels[name]) - np.asarray(minus.states.channels[name])) / (2 * h)
        scale = np.max(np.abs(fd)) + 1e-12
        np.testing.assert_allclose(exact, fd, atol=1e-5 * scale, rtol=1e-4, err_msg=name)
    ku = np.asarray(pad.understeer_gradient)
    assert ku.shape == (len(AY),) and np.all(np.isfinite(ku))
    np.testing.assert_allclose(
        ku, np.mean((np.asarray(plus.states.channels["road_wheel_angle"])[:, :2] - np.asarray(
            minus.states.channels["road_wheel_angle"])[:, :2]) / (2 * h), axis=1) * GRAVITY, rtol=1e-4)


def test_one_program_serves_every_condition_pair(car, pad):
    """A point of the curve found again from ``radius, ay``, from ``speed, yaw_rate`` and from
    ``speed, steer`` (its own speed set-point, yaw rate and steering): the same state."""
    k = 3
    point = jax.tree.map(lambda x: x[k], pad.states)
    speed, yaw, steer = float(point.speed_target), float(point.yaw_rate), float(
        np.radians(point.channels["steering_wheel_angle"]))
    for kwargs in ({"radius": RADIUS, "ay": float(AY[k])}, {"speed": speed, "yaw_rate": yaw},
                   {"speed": speed, "steer": steer}):
        again = steady_state(car, **kwargs)
        np.testing.assert_allclose(again.state.q, point.state.q, rtol=1e-8, atol=1e-11, err_msg=str(kwargs))
        np.testing.assert_allclose(again.state.u, point.state.u, rtol=1e-8, atol=1e-9, err_msg=str(kwargs))


def test_beyond_the_grip_limit_no_steady_state(car):
    """A lateral acceleration the tyres cannot give: a named error, no NaN; on the curve the
    points from the limit on come back not ok."""
    with pytest.raises(SetupError, match="no steady state at radius = 50, ay = 29.4"):
        steady_state(car, radius=RADIUS, ay=3.0 * GRAVITY)
    ay = np.concatenate([AY[:5], [2.5 * GRAVITY]])
    curve = skid_pad(car, RADIUS, ay)
    np.testing.assert_array_equal(curve.ok, [True] * 5 + [False])


@pytest.mark.parametrize("kwargs, match", [
    ({"speed": 20.0}, "exactly two of speed, radius, ay, yaw_rate, steer"),
    ({"radius": 50.0, "yaw_rate": 0.3}, "radius and yaw_rate do not fix the speed"),
    ({"speed": -1.0, "yaw_rate": 0.0}, "speed = -1.0 is out of range"),
    ({"radius": 0.0, "ay": 3.0}, "radius = 0.0 is out of range"),
])
def test_bad_conditions_are_refused(car, kwargs, match):
    with pytest.raises(ParameterError, match=match):
        steady_state(car, **kwargs)


def test_bad_skid_pad_arguments_are_refused(car):
    with pytest.raises(ParameterError, match="radius = -5"):
        skid_pad(car, -5.0)
    with pytest.raises(ParameterError, match="ay must be a non-empty, increasing"):
        skid_pad(car, 50.0, [3.0, 2.0])


def test_cli_skid_pad_json_and_files(car, pad, tmp_path):
    """``jaxveh simulate skid-pad --json`` (R = 50 m, root finding): the understeer gradient
    at the first point equals a central difference of two steady states; the curve, CSV and
    PNG are written. Six points, as the fixture's curve: the compiled program is reused."""
    result = CliRunner().invoke(app, ["simulate", "skid-pad", "--ay-max-g", "0.3", "--json", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["radius_m"] == 50.0 and report["points"] == 6 and report["method"].startswith("steady states")
    curve = report["curve"]
    np.testing.assert_allclose(curve["ay_g"], np.arange(1, 7) * 0.05, rtol=1e-10)
    h = 1e-2
    delta = [np.mean(np.asarray(steady_state(car, radius=50.0, ay=0.05 * GRAVITY + s * h).channels[
        "road_wheel_angle"])[:2]) for s in (1.0, -1.0)]
    np.testing.assert_allclose(report["understeer_gradient_deg_per_g"], (delta[0] - delta[1]) / (2 * h) * GRAVITY,
                               rtol=1e-4)
    np.testing.assert_allclose(np.asarray(curve["delta_dynamic_deg"]) + report["kinematic_steer_deg"],
                               curve["road_wheel_angle_deg"], rtol=1e-12)
    np.testing.assert_allclose(report["kinematic_steer_deg"], np.degrees(float(car.params.vehicle.wheelbase) / 50.0))
    assert report["max_residual"] < 1e-8 and not report["limit_reached"]
    header = (tmp_path / "skid_pad.csv").read_text().splitlines()[0].split(",")
    assert header[:3] == ["ay_g", "speed_kmh", "steering_wheel_angle_deg"] and "fz_rr_n" in header
    assert (tmp_path / "skid_pad.png").stat().st_size > 10_000
    assert json.loads((tmp_path / "skid_pad.json").read_text())["points"] == 6
    # --param: a stiffer front anti-roll bar and first chassis mode, as the API's with_params
    settings = {"arb_rates[0]": 2.0 * float(car.params.arb_rates[0]), "chassis.stiffness_scale[0]": 3.0}
    args = [a for path, value in settings.items() for a in ("--param", f"{path}={value!r}")]
    result = CliRunner().invoke(app, ["simulate", "skid-pad", "--ay-max-g", "0.3", "--json", *args])
    assert result.exit_code == 0, result.output
    changed = json.loads(result.stdout)
    assert changed["params"] == settings
    api = skid_pad(with_params(car, settings), RADIUS, np.arange(1, 7) * 0.05 * GRAVITY)
    np.testing.assert_allclose(changed["understeer_gradient_deg_per_g"], float(api.understeer_gradient[0]), rtol=1e-9)
    assert abs(changed["understeer_gradient_deg_per_g"] - report["understeer_gradient_deg_per_g"]) > 1e-4


@pytest.mark.parametrize("args, match", [
    (["--form", "library"], "fast car only"),
    (["--radius", "0"], "--radius must be > 0"),
    (["--ay-step-g", "0"], "ay step = 0.0 g"),
    (["--param", "arb_rate[0]=1"], "CarParams has no field 'arb_rate'"),
    (["--param", "coupling"], "expected PATH=VALUE"),
    (["--param", "coupling=2"], "coupling must lie in [0, 1]"),
])
def test_cli_skid_pad_refuses_bad_options(args, match):
    result = CliRunner().invoke(app, ["simulate", "skid-pad", *args, "--json"])
    assert result.exit_code == 2 and match in result.output


def test_conditions_are_listed():
    assert CONDITIONS == ("speed", "radius", "ay", "yaw_rate", "steer")
    np.testing.assert_array_equal(condition_kinds(("radius", "ay")), [1, 2])


@pytest.mark.slow
def test_steady_state_gradient_equals_central_difference(car):
    """Reverse-mode gradient of the roll angle at 0.5 g on the 50 m circle (implicit function
    theorem through Newton) w.r.t. the front anti-roll-bar rate, a front hard point and the
    first modal stiffness multiplier, against central differences."""
    kinds = condition_kinds(("radius", "ay"))
    values = jnp.asarray([RADIUS, 0.5 * GRAVITY])

    def roll(params):
        c = eqx.tree_at(lambda x: x.params, car, params)
        return compiled_core(c, kinds, values)[0].channels["roll"]

    grad = eqx.filter_jit(eqx.filter_grad(roll))(car.params)
    p = car.params
    knobs = [
        (lambda q: q.arb_rates, lambda g: g.arb_rates, 0, 1e-3 * float(p.arb_rates[0])),
        (lambda q: q.chassis.stiffness_scale, lambda g: g.chassis.stiffness_scale, 0, 1e-3),
    ]
    for where, read, index, h in knobs:
        leaf = where(p)
        shifted = [eqx.tree_at(where, p, leaf.at[index].add(s * h)) for s in (1.0, -1.0)]
        fd = (float(roll(shifted[0])) - float(roll(shifted[1]))) / (2 * h)
        np.testing.assert_allclose(float(read(grad)[index]), fd, rtol=1e-4, atol=1e-9)
