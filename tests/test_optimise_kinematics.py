"""The kinematic objectives (optimise: ``bump_steer``, ``camber_gain``): each corner's toe-in
and camber change per metre of its own travel at the design pose, from the fast car's exact
corner solve, against the library's quarter car (an independent exact assembly of the same
hard points) differentiated by central differences; mirror symmetry; the flexible car at
its undeformed design pose equals the rigid one; their derivatives with respect to hard
points against central differences; study files name them with a corner or an axle.
"""

import textwrap
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import optimise
from jaxveh import ParameterError, vehicle

#: Central-difference step of the wheel travel and of a hard point (m): the quarter car
#: solves its links to round-off, so the quotient's round-off is ~1e-11 / 2e-4 relative to
#: the angle; the truncation error is h^2 times the third derivative (~1e-8 relative).
TRAVEL_STEP, POINT_STEP = 1e-4, 1e-5
RTOL = 1e-6
#: Hard points moved in the derivative test: front inner track-rod joint L (bump steer)
#: and front upper-wishbone outer joint H (camber gain), their z (m).
PATHS = ("vehicle.hard_points_front.points[7, 2]", "vehicle.hard_points_front.points[6, 2]")
SPECS = (optimise.objective_spec("bump_steer", {"corner": "front_left"}),
         optimise.objective_spec("camber_gain", {"corner": "front_left"}))


@pytest.fixture(scope="module")
def rigid():
    return vehicle.load_car(modes=0)


@pytest.fixture(scope="module")
def rates(rigid):
    return np.asarray(jax.jit(optimise.suspension_kinematics)(rigid))


def _quarter_car_rates(car, axle):
    """(toe-in, camber top outwards) per m of travel (deg/m) of the library quarter car of
    ``axle`` by central differences in its wheel-centre travel."""
    system, params = vehicle.quarter_car(car.params.vehicle, axle)

    def angles(bump):
        _, out = vehicle.quarter_car_kinematics(system, params, bump, 0.0)
        return np.degrees([float(out["toe"]), float(out["camber"])])

    return (angles(TRAVEL_STEP) - angles(-TRAVEL_STEP)) / (2.0 * TRAVEL_STEP)


@pytest.mark.parametrize("axle", ["front", "rear"])
def test_equal_the_library_quarter_car(rigid, rates, axle):
    """bump_steer and camber_gain of both wheels of an axle, and the axle's, equal the
    quarter car's toe-in and camber derivatives (1e-6 relative)."""
    toe, camber = _quarter_car_rates(rigid, axle)
    wheels = [c for c in vehicle.CORNERS if c.startswith(axle)] + [axle]
    for corner in wheels:
        assert float(optimise._objectives._bump_steer(rates, corner)) == pytest.approx(toe, rel=RTOL)
        assert float(optimise._objectives._camber_gain(rates, corner)) == pytest.approx(camber, rel=RTOL)
    assert camber < 0.0  # the double wishbone's top leans in as the wheel rises


def test_mirror_symmetry_and_undeformed_flexible_car(rigid, rates):
    """Left and right wheels have the same toe-in and mirrored camber rates (1e-12); the
    flexible car at its design pose (modal coordinates zero) has the rigid car's rates."""
    np.testing.assert_allclose(rates[1, 3], rates[0, 3], rtol=1e-12)
    np.testing.assert_allclose(rates[3, 4], -rates[2, 4], rtol=1e-12)
    flexible = np.asarray(jax.jit(optimise.suspension_kinematics)(vehicle.load_car(modes=2)))
    np.testing.assert_allclose(flexible, rates, rtol=1e-12, atol=1e-14)


def test_derivatives_with_respect_to_hard_points(rigid):
    """Forward-mode derivatives of both objectives with respect to the z of front L and H
    (through the kinematic map's rebuild) equal central differences of the same program."""
    base = np.asarray([float(optimise.get_leaf(rigid.params, p)) for p in PATHS])

    def values(x):
        params = optimise.set_leaves(rigid.params, dict(zip(PATHS, x)))
        return optimise.objective_values(eqx.tree_at(lambda c: c.params, rigid, params), SPECS)

    evaluate = jax.jit(values)
    jac = np.asarray(jax.jit(jax.jacfwd(values))(jnp.asarray(base)))
    for j in range(len(PATHS)):
        step = np.zeros_like(base)
        step[j] = POINT_STEP
        fd = (np.asarray(evaluate(jnp.asarray(base + step))) - np.asarray(evaluate(jnp.asarray(base - step)))) / (
            2.0 * POINT_STEP)
        np.testing.assert_allclose(jac[:, j], fd, rtol=1e-5, atol=1e-6 * np.abs(jac).max())
    assert abs(jac[0, 0]) > 1.0  # the track-rod height steers: deg/m per m


def test_study_files_name_a_corner_or_an_axle(tmp_path):
    """A study's bump_steer takes a corner or an axle; another name is refused by name."""
    text = textwrap.dedent("""
        [study]
        modes = 0
        [[variables]]
        path = "vehicle.hard_points_front.points[7, 2]"
        lower = 0.30
        upper = 0.33
        [objective]
        name = "bump_steer"
        corner = "{corner}"
        target = 0.0
        [[constraints]]
        name = "camber_gain"
        corner = "front"
        "<=" = -20.0
    """)
    path = tmp_path / "bump.toml"
    path.write_text(text.format(corner="front"))
    study = optimise.load_optimisation_study(path)
    assert dict(study.terms[0].spec.settings) == {"corner": "front"}
    path.write_text(text.format(corner="middle"))
    with pytest.raises(ParameterError, match="objective.corner = 'middle' is not allowed: one of front_left, "
                                             "front_right, rear_left, rear_right, front, rear"):
        optimise.load_optimisation_study(path)
    with pytest.raises(ParameterError, match="corner = 'middle' is not allowed"):
        optimise.bump_steer(vehicle.load_car(modes=0), corner="middle")


def test_shipped_front_kinematics_study(tmp_path):
    """The shipped study (experiments/studies/front_kinematics.toml: front L z, M z, H z for
    zero bump steer with the camber gain held at -25 deg/m by an equality) converges with
    SLSQP; its optimum car file, read back, gives the library quarter car (an independent
    assembly) zero bump steer (below 1e-4 deg/m; the shipped car: -1.14) and the held
    camber gain (1e-5 relative)."""
    root = Path(__file__).resolve().parents[1] / "experiments" / "studies"
    study = optimise.load_optimisation_study(root / "front_kinematics.toml", out=tmp_path)
    result = optimise.optimise_study(study)
    assert result.converged, result.message
    files = optimise.write_outputs(result)
    car = vehicle.load_car(files["vehicle"], modes=0)
    toe, camber = _quarter_car_rates(car, "front")
    assert abs(toe) < 1e-4 and camber == pytest.approx(-25.0, rel=1e-5)
    assert result.evaluations <= 40
