"""optimise: variable selection, bounds, gradients, and the two chapter-3 worked examples."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize

import jaxveh.analytic as analytic
from jaxveh.analytic._maps import minimum_stiffness
from jaxveh.params import load_analytic_vehicle
from optimise import Problem, Variable, get_leaf, set_leaves
from optimise.examples import minimum_chassis_stiffness, roll_distribution_for_understeer

from helpers import central_difference


@pytest.fixture(scope="module")
def vehicle():
    return load_analytic_vehicle()


def test_select_and_set_by_name(vehicle):
    v = set_leaves(vehicle, {"kC": 1000.0, "tyre.scale_rear": 1.5})
    assert float(get_leaf(v, "kC")) == 1000.0
    assert float(v.tyre.scale_rear) == 1.5
    with pytest.raises(ValueError, match=r"parameter path 'tyre.grip': AxleTyre has no field 'grip'"):
        get_leaf(vehicle, "tyre.grip")


def test_bounds_map_round_trip_and_errors(vehicle):
    problem = Problem(vehicle, (Variable("kC", 10.0, 1e6, log=True), Variable("kF", 100.0, 1e5)), lambda v: v.kC)
    values = {"kC": 2000.0, "kF": 5000.0}
    back = problem.to_values(problem.to_z(values))
    assert float(back["kC"]) == pytest.approx(2000.0, rel=1e-12)
    assert float(back["kF"]) == pytest.approx(5000.0, rel=1e-12)
    with pytest.raises(ValueError, match=r"initial kC = 1.0 must lie strictly inside \(10.0, 1000000.0\)"):
        problem.to_z({"kC": 1.0, "kF": 5000.0})
    with pytest.raises(ValueError, match="need lower < upper"):
        Problem(vehicle, (Variable("kC", 5.0, 1.0),), lambda v: v.kC)


def test_objective_gradient_in_design_space(vehicle):
    problem = Problem(
        vehicle,
        (Variable("lam", 0.05, 0.95),),
        lambda v: analytic.understeer_gradient(v),
        apply=lambda v, values: analytic.with_distribution(v, lam=values["lam"], mu=0.7),
    )
    f = lambda z: problem.objective(problem.build(z))
    z0 = np.array([0.3])
    np.testing.assert_allclose(jax.grad(f)(jnp.asarray(z0)), central_difference(f, z0, 1e-6), rtol=1e-6)


@pytest.mark.slow
def test_example_a_matches_bisection(vehicle):
    out = minimum_chassis_stiffness(vehicle)
    reference = minimum_stiffness(vehicle, "chi_error", 0.02, (0.3, 0.7))["mu"]
    assert out["mu"] == pytest.approx(reference, rel=2e-3)
    assert out["result"].constraints[0] <= 1e-3  # worst error within 0.1 % of the 2 % limit


def test_example_b_hits_target(vehicle):
    target_ku = 0.76
    out = roll_distribution_for_understeer(target_ku, vehicle, mu=1.0)
    assert out["ku_deg_per_g"] == pytest.approx(target_ku, abs=1e-5)
    flex = analytic.with_distribution(vehicle, mu=1.0)
    ku = lambda lam: float(analytic.understeer_gradient(analytic.with_distribution(flex, lam=lam)) * analytic.RAD_PER_MS2_TO_DEG_PER_G) - target_ku
    assert out["lam"] == pytest.approx(scipy.optimize.brentq(ku, 0.05, 0.95), abs=1e-4)
