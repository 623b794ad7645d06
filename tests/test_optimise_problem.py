"""optimise: variable selection, bounds, gradients, input checks and the two chapter-3 worked examples."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest
import scipy.optimize
from helpers import central_difference

import jaxveh.analytic as analytic
from jaxveh.analytic._maps import minimum_stiffness
from jaxveh.params import ParameterError, load_analytic_vehicle
from optimise import Problem, Variable, get_leaf, set_leaves, solve
from optimise.examples import minimum_chassis_stiffness, roll_distribution_for_understeer


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
    def ku(lam):
        v = analytic.with_distribution(flex, lam=lam)
        return float(analytic.understeer_gradient(v) * analytic.RAD_PER_MS2_TO_DEG_PER_G) - target_ku

    assert out["lam"] == pytest.approx(scipy.optimize.brentq(ku, 0.05, 0.95), abs=1e-4)


@pytest.mark.parametrize(
    "variables, match",
    [
        ((Variable("m", 100.0, 400.0),), r"parameter path 'm': AnalyticVehicle\.m is derived from other fields"),
        ((Variable("kC", 1.0, float("inf")),), r"variable 'kC': bounds must be finite"),
        ((Variable("kC", 1.0, 10.0), Variable("kC", 2.0, 20.0)), r"design variable names must be unique"),
        ((Variable("kC", -1.0, 10.0, log=True),), r"variable 'kC': log scale needs lower > 0"),
        ((), r"Problem needs at least one design variable"),
    ],
)
def test_problem_definition_errors(vehicle, variables, match):
    with pytest.raises(ParameterError, match=match):
        Problem(vehicle, variables, lambda v: v.kC)


def test_solve_settings_and_initial_values(vehicle):
    problem = Problem(vehicle, (Variable("kC", 10.0, 1e5, log=True),), lambda v: analytic.chi(v))
    with pytest.raises(ParameterError, match=r"initial values missing for design variable\(s\) \['kC'\]"):
        solve(problem, {})
    for settings, match in (
        ({"inner_steps": 0}, r"inner_steps must be a Python int >= 1"),
        ({"rho": 0.0}, r"rho must lie in \(0, inf\)"),
        ({"rho_growth": 0.5}, r"rho_growth must lie in \[1, inf\)"),
        ({"constraint_tol": -1.0}, r"constraint_tol must lie in \(0, inf\)"),
    ):
        with pytest.raises(ParameterError, match=match):
            solve(problem, {"kC": 1000.0}, **settings)


def test_optimiser_leaving_the_physical_range_raises_named_error(vehicle):
    """Bounds that admit a negative roll stiffness: the traced check stops the solve with the
    field's name instead of letting NaN or nonsense through."""
    problem = Problem(vehicle, (Variable("kF", -5000.0, 20000.0),), lambda v: analytic.roll_stiffness_proportion(v))
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"AnalyticVehicle\.kF must lie in \[0, inf\)"):
        solve(problem, {"kF": 1000.0}, optax.sgd(1.0), inner_steps=50, outer_steps=1)


@pytest.mark.parametrize("pull", [0.1, 0.9])
def test_equality_constraint_pins_understeer_gradient(vehicle, pull):
    """An equality ku(λ) = 0.76 deg/g with an objective pulling λ towards ``pull`` (below and
    above the root, so the multiplier takes either sign): the solve ends on brentq's λ
    (1e-4) with the equality met, where an inequality would have been inactive one side."""
    flex = analytic.with_distribution(vehicle, mu=1.0)

    def ku(v):
        return analytic.understeer_gradient(v) * analytic.RAD_PER_MS2_TO_DEG_PER_G

    def objective(v):
        return (analytic.roll_stiffness_proportion(v) - pull) ** 2

    problem = Problem(flex, (Variable("lam", 0.05, 0.95),), objective,
                      apply=lambda v, values: analytic.with_distribution(v, lam=values["lam"]),
                      equalities=(lambda v: (ku(v) - 0.76) / 0.01,))
    result = solve(problem, {"lam": 0.5}, optax.adam(0.02), inner_steps=400, outer_steps=20)
    root = scipy.optimize.brentq(lambda lam: float(ku(analytic.with_distribution(flex, lam=lam))) - 0.76, 0.05, 0.95)
    assert result.values["lam"] == pytest.approx(root, abs=1e-4)
    assert result.constraints == [] and abs(result.equalities[0]) < 1e-3
    assert result.history[-1]["max_violation"] == pytest.approx(abs(result.equalities[0]), rel=1e-6, abs=1e-12)
