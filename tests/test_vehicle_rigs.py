"""Kinematic rigs on the assembled car (Figs. 6.11, 6.12): against the library's quarter car,
mirror symmetry, roll stiffness against the rate formulas and Appendix A, the anti-roll bar
moving λ, stiff modes tending to the rigid car, a gradient, failure naming the link, and the
``jaxveh rig`` contract."""

import json
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from typer.testing import CliRunner

from jaxveh import multibody as mb, vehicle
from jaxveh.cli._main import app

TRAVEL = jnp.linspace(-0.05, 0.05, 5)
ROLL = jnp.radians(jnp.asarray([-2.0, -1.0, 0.0, 1.0, 2.0]))


@pytest.fixture(scope="module")
def rigid():
    return vehicle.load_car(modes=0)


@pytest.fixture(scope="module")
def bump_front(rigid):
    return vehicle.bump_rig(rigid, TRAVEL, "front")


@pytest.fixture(scope="module")
def roll(rigid):
    return vehicle.roll_rig(rigid, ROLL)


def test_bump_curves_equal_the_quarter_car(bump_front):
    """Front-left camber, toe, track and wheel centre equal the library quarter car's."""
    system, params = vehicle.quarter_car()
    for k, h in enumerate(np.asarray(TRAVEL)):
        _, out = vehicle.quarter_car_kinematics(system, params, h, 0.0)
        assert abs(float(bump_front["camber"][k, 0] - out["camber"])) < 1e-9
        assert abs(float(bump_front["toe"][k, 0] - out["toe"])) < 1e-9
        assert abs(float(bump_front["track"][k] - out["track"])) < 1e-9
        assert abs(float(bump_front["wheel_centre_y"][k, 0] - out["wheel_centre"][1])) < 1e-9
        assert abs(float(bump_front["travel"][k, 0]) - h) < 1e-12
    assert np.all(np.asarray(bump_front["worst"]) == -1) and float(np.max(bump_front["gap"])) < 1e-10


def test_right_wheel_mirrors_left(bump_front, roll):
    for key in ("camber", "toe", "fz"):
        np.testing.assert_allclose(bump_front[key][:, 1], bump_front[key][:, 0], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(bump_front["wheel_centre_y"][:, 1], -bump_front["wheel_centre_y"][:, 0], atol=1e-12)
    # rolling right is rolling left mirrored
    np.testing.assert_allclose(roll["camber"][::-1, [1, 0, 3, 2]], roll["camber"], atol=1e-12)
    np.testing.assert_allclose(roll["moment"][::-1], -roll["moment"], rtol=1e-9, atol=1e-9)


def test_pad_load_at_rest_is_the_corner_load(rigid, bump_front):
    """At zero travel the pad carries the static corner load (the preload was set for it)."""
    loads = vehicle.static_corner_loads(rigid.params.vehicle)
    np.testing.assert_allclose(bump_front["fz"][2], loads[:2], rtol=1e-9)
    assert np.all(np.diff(np.asarray(bump_front["fz"][:, 0])) > 0)  # more load in bump


def test_pad_load_slope_is_the_wheel_rate(rigid):
    """d F_z / d z at the design position equals the wheel rate of the formulas."""
    slope = jax.jvp(lambda h: vehicle.bump_rig(rigid, h, "rear")["fz"][:, 0], (jnp.zeros(1),), (jnp.ones(1),))[1]
    rates = vehicle.car_rates(rigid)
    # both wheels move: the pad also carries the anti-roll bar? No: heave does not twist it.
    np.testing.assert_allclose(float(slope[0]), float(rates["rear"].wheel_rate), rtol=2e-3)


def test_roll_stiffness_matches_formula_and_appendix_a(rigid, roll):
    measured = np.asarray(roll["stiffness"][2]) * math.pi / 180.0  # N m/deg at zero roll
    rates = vehicle.car_rates(rigid)
    formula = [float(rates[a].roll_stiffness_nm_per_deg) for a in ("front", "rear")]
    np.testing.assert_allclose(measured, formula, rtol=0.01)
    np.testing.assert_allclose(measured, [205.0, 175.0], rtol=0.01)
    # the moment is the integral of the stiffness: a central difference of it
    h = float(ROLL[3] - ROLL[2])
    np.testing.assert_allclose((roll["moment"][3] - roll["moment"][1]) / (2 * h), roll["stiffness"][2], rtol=0.02)


def test_anti_roll_bar_moves_lambda_as_predicted(rigid, roll):
    stiffer = eqx.tree_at(lambda c: c.params.arb_rates, rigid, rigid.params.arb_rates * jnp.asarray([2.0, 1.0]))
    measured = vehicle.roll_rig(stiffer, ROLL)["stiffness"][2]
    before = roll["stiffness"][2]
    lam_rig = [float(k[0] / (k[0] + k[1])) for k in (before, measured)]
    r0, r1 = vehicle.car_rates(rigid), vehicle.car_rates(stiffer)
    lam_formula = [float(vehicle.roll_stiffness_distribution(r["front"], r["rear"])) for r in (r0, r1)]
    assert lam_rig[1] > lam_rig[0] + 0.05
    np.testing.assert_allclose(lam_rig[1] - lam_rig[0], lam_formula[1] - lam_formula[0], rtol=0.02)
    np.testing.assert_allclose(measured[1], before[1], rtol=1e-12)  # rear untouched


def test_roll_camber_and_steer_are_odd(roll):
    np.testing.assert_allclose(roll["camber"][2], 0.0, atol=1e-12)
    assert float(roll["camber"][4, 0]) * float(roll["camber"][0, 0]) < 0


@pytest.mark.slow
def test_roll_camber_gradient_wrt_hard_point(rigid):
    """d(roll camber at 1 deg)/d(z of the front upper ball joint H) vs central differences."""
    from jaxveh.params import HARD_POINT_NAMES

    row = HARD_POINT_NAMES.index("H")

    def camber(dz):
        pts = rigid.params.vehicle.hard_points_front.points
        car = eqx.tree_at(lambda c: c.params.vehicle.hard_points_front.points, rigid, pts.at[row, 2].add(dz))
        return vehicle.roll_rig(car, jnp.radians(jnp.ones(1)))["camber"][0, 0]

    slope = jax.jvp(camber, (jnp.asarray(0.0),), (jnp.asarray(1.0),))[1]
    h = 1e-4
    fd = (float(camber(jnp.asarray(h))) - float(camber(jnp.asarray(-h)))) / (2 * h)
    assert abs(float(slope)) > 1e-3
    np.testing.assert_allclose(float(slope), fd, rtol=1e-5)


def test_steer_rig_is_antisymmetric_and_plausible(rigid):
    angles = jnp.radians(jnp.asarray([-120.0, -90.0, 0.0, 90.0, 120.0]))
    r = vehicle.steer_rig(rigid, angles)
    steer = np.asarray(r["steer"])
    np.testing.assert_allclose(steer[::-1, ::-1], -steer, atol=1e-12)
    assert steer[4, 0] > steer[4, 1] > 0  # turning left: the inner (left) wheel steers more
    assert 2.5 < 120.0 / np.degrees(steer[4].mean()) < 6.0  # overall steering ratio, FSAE-typical
    assert np.isnan(float(r["ackermann"][2])) and np.isfinite(np.asarray(r["ackermann"])[[0, 1, 3, 4]]).all()
    assert 0.0 < float(r["scrub_radius"][2, 0]) < 0.08


@pytest.mark.slow
def test_flexible_rigs_tend_to_rigid_with_stiff_modes(rigid, bump_front):
    flexible = vehicle.load_car(modes=6)
    soft = vehicle.bump_rig(flexible, TRAVEL, "front")
    stiff_car = eqx.tree_at(lambda c: c.params.chassis.stiffness_scale, flexible,
                            flexible.params.chassis.stiffness_scale * 1e6)
    stiff = vehicle.bump_rig(stiff_car, TRAVEL, "front")
    assert np.all(np.asarray(soft["worst"]) == -1) and np.all(np.asarray(stiff["worst"]) == -1)
    for key in ("camber", "toe", "fz"):
        np.testing.assert_allclose(stiff[key], bump_front[key], rtol=1e-5, atol=1e-8)
    # the flexible chassis gives way under the pads: less load at full bump
    assert float(soft["fz"][4, 0]) < float(bump_front["fz"][4, 0])


def test_unreachable_travel_names_the_link(rigid):
    r = vehicle.bump_rig(rigid, jnp.asarray([0.0, 0.0, 0.0, 0.0, 0.6]), "front")
    message = r"sweep point 4 of 5: link front_(left|right)\.\w+\[length\] does not close \(largest gap \d"
    with pytest.raises(mb.AssemblyError, match=message):
        vehicle.check_rig(rigid, "bump rig", r)


def test_rig_bump_json_contract(rigid):
    result = CliRunner().invoke(app, ["rig", "bump", "--modes", "0", "--points", "5", "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    for axle in ("front", "rear"):
        block = out[axle]
        keys = ("travel_mm", "camber_deg", "toe_deg", "track_mm", "fz_n")
        assert all(len(block[k]) == 5 for k in keys)
        np.testing.assert_allclose(block["travel_mm"], np.linspace(-50, 50, 5), atol=1e-9)
    system, params = vehicle.quarter_car()
    _, qc = vehicle.quarter_car_kinematics(system, params, 0.025, 0.0)
    assert out["front"]["camber_deg"][3] == pytest.approx(math.degrees(float(qc["camber"])), abs=1e-8)
    assert out["front"]["toe_deg"][3] == pytest.approx(math.degrees(float(qc["toe"])), abs=1e-8)
    assert out["front"]["track_mm"][3] == pytest.approx(1e3 * float(qc["track"]), abs=1e-6)


def test_rig_commands_write_files(tmp_path):
    for name, extra in (("steer", []), ("roll", [])):
        result = CliRunner().invoke(app, ["rig", name, "--modes", "0", "--points", "5", "--out", str(tmp_path)] + extra)
        assert result.exit_code == 0, result.output
        assert (tmp_path / f"{name}.json").is_file() and (tmp_path / f"{name}.png").is_file()
        assert list(tmp_path.glob(f"{name}_*.csv"))
    roll = json.loads((tmp_path / "roll.json").read_text())
    assert roll["roll_stiffness_nm_per_deg"]["front"] == pytest.approx(205.0, rel=0.01)
