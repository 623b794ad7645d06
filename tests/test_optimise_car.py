"""Design optimisation on the car (optimise._objectives, optimise._optimise_study,
``jaxveh optimise``): the traced λ rule against jaxveh.analysis, every
skid-pad objective's forward-mode derivative against central differences, the first
coupled chassis mode's eigenvalue rule, a known optimum (the λ of a target understeer
gradient, by SciPy's brentq on the library's own skid-pad) recovered to 1e-4, a failed
steady state reported with its history, bad study files refused by name, the CLI's JSON
contract and the optimum's car file read back.

Compile cost: the car's forward-mode programs (second derivatives of its equations through
the Newton solves) take minutes on two cores for the 6-mode car, so the car tests use the
2-mode car (``MODES``): the same code paths, the mode count is structure only. Every car
test shares one study (:data:`STUDY`: one compiled program), whose constraints are far
from active, so its optimum is the understeer-gradient target's alone.
"""

import difflib
import json
import textwrap
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize
from typer.testing import CliRunner

import optimise
from jaxveh import GRAVITY, ParameterError
from jaxveh.analysis import arb_rates_for_distribution
from jaxveh.cli import app
from jaxveh.manoeuvre import skid_pad
from jaxveh.vehicle import load_car, with_params

#: Chassis modes of the car tests (module docs).
MODES = 2
#: ay (g) and radius (m) of the understeer gradient.
AY_G, RADIUS = 0.05, 50.0
#: λ of the forward model's bracket and of the design variable's bounds.
LAM_BOUNDS = (0.3, 0.7)
#: Central-difference step in the unconstrained variable z and the agreement asked: Newton
#: stops below 1e-11 relative (quadratic convergence leaves far less), so a quotient over
#: 2e-4 carries < 1e-7 relative round-off; the step's truncation error is ~1e-8 relative.
FD_STEP, FD_RTOL = 1e-4, 1e-5
#: The optimiser's λ against brentq's (the brief's 1e-4; brentq to 1e-12).
LAMBDA_TOL = 1e-4

STUDY = """
[study]
name = "known"
model = "car"
modes = {modes}

[[variables]]
path = "lambda"
lower = 0.3
upper = 0.7
initial = 0.5

[objective]
name = "understeer_gradient"
target = {target!r}
scale = 0.1
ay_g = {ay}
radius = {radius}

# far from active: the optimum is the target's alone; their Jacobian rows are checked
[[constraints]]
name = "roll_gradient"
"<=" = 50.0
[[constraints]]
name = "camber_gradient"
corner = "front_right"
"<=" = 50.0
[[constraints]]
name = "rear_steer_gradient"
">=" = -50.0
[[constraints]]
name = "steering_sensitivity"
"<=" = 1000.0

[optimiser]
method = "{method}"
steps = {steps}
tolerance = 1e-10
"""


def _write(folder, text, name="study.toml"):
    path = folder / name
    path.write_text(textwrap.dedent(text))
    return path


def _ku_library(car, lam):
    """The forward model: ku (deg/g) by jaxveh's own skid-pad, λ by its own bar rule."""
    rates = np.asarray(arb_rates_for_distribution(car, lam))
    c = with_params(car, {"arb_rates[0]": float(rates[0]), "arb_rates[1]": float(rates[1])})
    return float(skid_pad(c, RADIUS, [AY_G * GRAVITY]).understeer_gradient[0])


@pytest.fixture(scope="module")
def study_path(tmp_path_factory):
    """The study with the target 0 for now (:func:`known` sets the real one: the target
    changes no compiled program, it is applied on the host)."""
    folder = tmp_path_factory.mktemp("study")
    return _write(folder, STUDY.format(modes=MODES, target=0.0, ay=AY_G, radius=RADIUS, method="lbfgs", steps=30))


@pytest.fixture(scope="module")
def design(study_path):
    return optimise.build_design(optimise.load_optimisation_study(study_path))


def _ku(design, lam):
    """The forward model: the study's understeer gradient (deg/g) at λ, values only."""
    return float(design.evaluate(np.asarray(design.problem.to_z({"lambda": lam})))[0][0])


@pytest.fixture(scope="module")
def known(design, study_path):
    """(target ku, brentq's λ, the study file with that target): the target is the forward
    model's mean of its values at 0.31 and 0.45, where ku falls monotonically with λ (on
    the 2-mode car: -0.10 deg/g at 0.3, -0.14 at 0.4, a minimum near 0.6), so its root is
    unique in the study's bounds."""
    low, high = 0.31, 0.45
    target = 0.5 * (_ku(design, low) + _ku(design, high))
    lam = scipy.optimize.brentq(lambda x: _ku(design, x) - target, low, high, xtol=1e-12)
    path = study_path.with_name("known.toml")
    path.write_text(study_path.read_text().replace("target = 0.0", f"target = {target!r}"))
    return target, lam, path


def test_traced_lambda_rule_equals_the_library():
    """arb_rates_for_lambda (traceable) equals jaxveh.analysis.arb_rates_for_distribution on
    both sides of the bars' limits (0.377-0.622), and traces under jit."""
    rigid = load_car(modes=0)
    coefficients = optimise.roll_rate_coefficients(rigid)
    lams = np.linspace(0.2, 0.8, 13)
    np.testing.assert_allclose(jax.jit(optimise.arb_rates_for_lambda)(coefficients, jnp.asarray(lams)),
                               arb_rates_for_distribution(rigid, lams), rtol=1e-12, atol=1e-12)


def test_matched_eigenvalue_derivative():
    """The matched eigenvalue's first-order perturbation rule against central differences,
    forward and reverse mode, on a damped oscillator chain (distinct complex pairs)."""
    n = 4
    k = np.diag(np.arange(1.0, n + 1) * 40.0) - np.diag(np.full(n - 1, 10.0), 1) - np.diag(np.full(n - 1, 10.0), -1)
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-k, -0.1 * np.eye(n)]])
    lam, vec = np.linalg.eig(a)
    ref = vec[:, np.argmin(np.abs(lam - lam[lam.imag > 0][np.argsort(np.abs(lam[lam.imag > 0]))[1]]))]
    da = np.random.default_rng(1).normal(size=a.shape)
    f = lambda t: jnp.stack(optimise.matched_eigenvalue(jnp.asarray(a) + t * da, jnp.asarray(ref)))  # noqa: E731
    h = 1e-6
    fd = (f(h) - f(-h)) / (2 * h)
    _, jvp = jax.jvp(f, (0.0,), (1.0,))
    np.testing.assert_allclose(jvp, fd, rtol=1e-6, atol=1e-8)
    grad = jax.grad(lambda t: f(t)[1])(0.0)
    np.testing.assert_allclose(grad, fd[1], rtol=1e-6)


@pytest.mark.slow
def test_objective_derivatives_equal_central_differences(design):
    """Every objective of the study (understeer gradient, steering sensitivity, roll, camber
    and rear steer gradients: one skid-pad point): the forward-mode Jacobian along λ equals
    a central difference of the same compiled values. (χ's program, four steady turns, is
    left out of the shared study for its compile time; its gradient is checked in
    tests/test_analysis_load_transfer.py, the same core.)"""
    z0 = np.asarray(design.problem.to_z({"lambda": 0.5}))
    values, jac = design.evaluate(z0)
    assert np.all(np.isfinite(values)) and values.shape == (len(design.specs),)
    plus, _ = design.evaluate(z0 + FD_STEP)
    minus, _ = design.evaluate(z0 - FD_STEP)
    fd = (plus - minus) / (2 * FD_STEP)
    for spec, d, c in zip(design.specs, jac[:, 0], fd):
        assert abs(d - c) <= FD_RTOL * max(abs(c), 1e-3), (spec.name, d, c)
    # each value is the library's own at λ = 0.5 (the understeer gradient by skid_pad)
    assert values[0] == pytest.approx(_ku_library(design.car, 0.5), rel=1e-9)


@pytest.mark.slow
def test_recovers_the_known_optimum(design, known):
    """L-BFGS finds brentq's λ of the target understeer gradient to 1e-4 and converges."""
    study = optimise.load_optimisation_study(known[2])
    result = optimise.optimise_study(study, design=design)
    assert result.converged, result.message
    assert abs(result.optimum["lambda"] - known[1]) < LAMBDA_TOL
    assert result.values["understeer_gradient"] == pytest.approx(known[0], abs=1e-6)
    assert all(c["violation"] < 0 for c in result.constraints)
    history = result.history
    assert history[0]["lambda"] == pytest.approx(0.5) and len(history) == result.iterations
    assert history[-1]["grad_norm"] <= 1e-10 < history[0]["grad_norm"]


@pytest.mark.slow
def test_failed_steady_state_keeps_the_history(design, known):
    """A steady state that fails mid-run (its values NaN from the third evaluation on) ends
    the run with OptimisationError naming it, the history so far and the last good design."""
    study = optimise.load_optimisation_study(known[2])
    study = study._replace(optimiser={**study.optimiser, "method": "adam", "steps": 10})
    calls = []

    def failing(z):
        calls.append(z)
        values, jac = design.evaluate(z)
        return (values * np.nan, jac) if len(calls) >= 3 else (values, jac)

    with pytest.raises(optimise.OptimisationError, match="failed simulation at iteration 2: understeer_gradient"):
        optimise.optimise_study(study, design=design._replace(evaluate=failing))
    calls.clear()
    result = optimise.optimise_study(study, design=design._replace(evaluate=failing), throw=False)
    assert result.failed and not result.converged and len(result.history) == 2
    assert np.isfinite(result.objective)


@pytest.mark.slow
def test_cli_contract_and_car_file(design, known, tmp_path):
    """``jaxveh optimise STUDY --out DIR --json``: one JSON object with optimum, objective,
    converged; the history as JSON and CSV; the optimum's car file, read back, gives the
    optimum's bar rates and its understeer gradient."""
    result = CliRunner().invoke(app, ["optimise", str(known[2]), "--out", str(tmp_path), "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert set(report["optimum"]) == {"lambda"} and isinstance(report["objective"], float)
    assert report["converged"] is True
    assert abs(report["optimum"]["lambda"] - known[1]) < LAMBDA_TOL
    saved = json.loads((tmp_path / "known.json").read_text())
    rows = (tmp_path / "known_history.csv").read_text().splitlines()
    assert len(rows) == 1 + len(saved["history"]) == 1 + saved["iterations"]
    assert rows[0].split(",")[:4] == ["iteration", "outer", "evaluations", "objective"]
    text = (tmp_path / "known_car.toml").read_text()
    assert text.count("arb_rate = ") == 2 and "# The optimum of the study 'known'" in text
    reloaded = load_car(tmp_path / "known_car.toml", modes=MODES)
    rates = arb_rates_for_distribution(design.car, report["optimum"]["lambda"])
    np.testing.assert_allclose(reloaded.params.arb_rates, rates, rtol=1e-9)
    assert set(saved["car_values"]) == {"arb_rates[0]", "arb_rates[1]"}
    ku = float(skid_pad(reloaded, RADIUS, [AY_G * GRAVITY]).understeer_gradient[0])
    assert ku == pytest.approx(known[0], abs=1e-5)


def _roll(design, lam):
    """The study's roll gradient (deg/g) at λ (its second objective), values only."""
    return float(design.evaluate(np.asarray(design.problem.to_z({"lambda": lam})))[0][1])


@pytest.mark.slow
def test_epsilon_constraint_front(design, known, tmp_path):
    """The ε-constraint sweep of the roll-gradient bound (SLSQP): a loose bound leaves the target's
    λ (brentq's, 1e-4); a bound below the roll gradient there is active at the optimum and
    moves λ to where the roll gradient equals it (brentq on the forward model, 1e-4),
    i.e. the feasible λ nearest the target's (ku falls monotonically with λ here); files
    and the CLI's JSON agree."""
    target, lam_star, path = known
    lam_active = lam_star - 0.03
    roll_star, eps = _roll(design, lam_star), _roll(design, lam_active)
    assert eps < roll_star - 1e-3, "the roll gradient must rise with lambda here for this test's bracket"
    # SLSQP, the method for active bounds (docs/objectives.md): L-BFGS inside the augmented
    # Lagrangian stops on its line search at round-off on the tight point, not converged
    text = path.read_text().replace('method = "lbfgs"', 'method = "slsqp"') + (
        f'\n[pareto]\nconstraint = "roll_gradient"\nvalues = [{roll_star + 0.5!r}, {eps!r}]\n')
    pareto_path = _write(tmp_path, text, "front.toml")
    study = optimise.load_optimisation_study(pareto_path, out=tmp_path / "out")
    assert study.pareto == optimise.ParetoSweep(constraint=0, values=(roll_star + 0.5, eps))
    front = optimise.pareto_front(study, design=design)
    loose, tight = front.results
    assert loose.converged and tight.converged, (loose.message, tight.message)
    assert abs(loose.optimum["lambda"] - lam_star) < LAMBDA_TOL
    root = scipy.optimize.brentq(lambda x: _roll(design, x) - eps, 0.3005, lam_star, xtol=1e-12)
    assert abs(tight.optimum["lambda"] - root) < LAMBDA_TOL
    report = optimise.pareto_report(front)
    assert [p["active"] for p in report["points"]] == [False, True]
    assert report["points"][1]["constrained_value"] == pytest.approx(eps, abs=1e-5)
    assert report["points"][1]["objective"] > report["points"][0]["objective"]
    files = optimise.write_pareto_outputs(front)
    assert json.loads(open(files["json"]).read())["points"][1]["bound"] == eps
    assert len(open(files["csv"]).read().splitlines()) == 3
    res = CliRunner().invoke(app, ["optimise", str(pareto_path), "--out", str(tmp_path / "cli"), "--json"])
    assert res.exit_code == 0, res.output
    cli = json.loads(res.stdout)
    assert [p["optimum"]["lambda"] for p in cli["points"]] == pytest.approx(
        [r.optimum["lambda"] for r in front.results], abs=1e-9)


def _slsqp_study(path, tmp_path, name, extra=""):
    text = path.read_text().replace('method = "lbfgs"', 'method = "slsqp"') + extra
    return optimise.load_optimisation_study(_write(tmp_path, text, name), out=tmp_path / "out")


#: Values linear in z with the shared study's structure (:func:`_synthetic`).
SYNTHETIC = {"understeer_gradient": (0.0, 1.0), "roll_gradient": (40.0, 100.0), "camber_gradient": (0.0, 0.0),
             "rear_steer_gradient": (0.0, 0.0), "steering_sensitivity": (1.0, 0.0)}


def _synthetic(design, fail_after=None):
    """An ``evaluate`` for the shared study's objectives: value = a + b z (SYNTHETIC), NaN
    from call ``fail_after`` on."""
    calls = {"n": 0}

    def evaluate(z):
        calls["n"] += 1
        a, b = (np.asarray([SYNTHETIC[s.name][i] for s in design.specs]) for i in (0, 1))
        values = a + b * float(z[0])
        if fail_after is not None and calls["n"] >= fail_after:
            values = values * np.nan
        return values, b[:, None]

    return evaluate


def test_slsqp_ends_on_an_active_bound(design, study_path, tmp_path):
    """SciPy's SLSQP (``method = "slsqp"``) on synthetic values with the shared study's
    structure, ku = z and the roll gradient 100 z + 40 (z the unconstrained variable): the
    target ku = 0.5 with roll <= 50 has its optimum on the bound, z = 0.1, where SLSQP ends
    (1e-9) converged in a few evaluations with its history; a non-finite evaluation ends it
    with OptimisationError carrying the history and the last good design."""
    study = _slsqp_study(study_path, tmp_path, "slsqp.toml")
    study = study._replace(terms=tuple(t._replace(target=0.5) for t in study.terms))
    res = optimise.optimise_study(study, design=design._replace(evaluate=_synthetic(design)))
    z = float(design.problem.to_z(res.optimum)[0])
    assert res.converged, res.message
    assert abs(z - 0.1) < 1e-9 and res.evaluations <= 15
    assert res.history[0]["evaluations"] == 1 and res.history[-1]["roll_gradient"] == pytest.approx(50.0, abs=1e-7)
    with pytest.raises(optimise.OptimisationError, match="failed simulation at iteration") as failed:
        optimise.optimise_study(study, design=design._replace(evaluate=_synthetic(design, fail_after=3)))
    assert failed.value.result.failed and len(failed.value.result.history) >= 1


def _synthetic_in_lambda(design, slope):
    """An ``evaluate`` whose understeer gradient is ``slope`` λ (the physical variable, not
    z) and whose other values are constant: its exact Jacobian in z through the bound map."""
    lower, upper = LAM_BOUNDS

    def evaluate(z):
        lam = float(design.problem.to_values(jnp.asarray(z))["lambda"])
        sig = (lam - lower) / (upper - lower)
        b = np.asarray([slope if s.name == "understeer_gradient" else 0.0 for s in design.specs])
        a = np.asarray([SYNTHETIC[s.name][0] for s in design.specs])
        return a + b * lam, (b * (upper - lower) * sig * (1.0 - sig))[:, None]

    return evaluate


@pytest.mark.parametrize("target, bound", [(0.9, LAM_BOUNDS[1]), (0.1, LAM_BOUNDS[0])])
def test_slsqp_ends_on_a_variable_bound(design, study_path, tmp_path, target, bound):
    """SLSQP on synthetic values ku = λ with a target outside λ's bounds: the optimum is
    on the bound, where SLSQP (working on λ's place in its bounds) ends converged, λ on the
    bound to 1e-9, in a few evaluations (in the unconstrained z the bound lies at infinity
    and the run crept towards it until its iteration limit)."""
    study = _slsqp_study(study_path, tmp_path, "bound.toml")
    study = study._replace(terms=tuple(t._replace(target=target) for t in study.terms))
    res = optimise.optimise_study(study, design=design._replace(evaluate=_synthetic_in_lambda(design, 1.0)))
    assert res.converged, res.message
    assert abs(res.optimum["lambda"] - bound) < 1e-9 and res.evaluations <= 10


@pytest.mark.parametrize("method", ["slsqp", "lbfgs"])
@pytest.mark.parametrize("value, z_star", [(45.0, 0.05), (95.0, 0.55)])
def test_equality_constraint(design, study_path, tmp_path, method, value, z_star):
    """An equality on synthetic values (roll gradient 100 z + 40, ku = z, target ku = 0.5):
    ``"==" = 45`` and ``"==" = 95`` hold the optimum at z = 0.05 and 0.55, either side of
    the target's (so the multiplier takes either sign; ``<= 95`` would be inactive), with
    SciPy's SLSQP and with the augmented Lagrangian around L-BFGS; converged, the equality
    met to 1e-7 and reported with its kind."""
    study = _slsqp_study(study_path, tmp_path, "equality.toml")
    opts = {**study.optimiser, "method": method, "outer_steps": 30}
    study = study._replace(terms=tuple(t._replace(target=0.5) for t in study.terms), optimiser=opts,
                           constraints=tuple(c._replace(kind="==", bound=value) if c.spec.name == "roll_gradient"
                                             else c for c in study.constraints))
    res = optimise.optimise_study(study, design=design._replace(evaluate=_synthetic(design)))
    assert res.converged, res.message
    assert float(design.problem.to_z(res.optimum)[0]) == pytest.approx(z_star, abs=1e-9)
    roll = next(c for c in res.constraints if c["name"] == "roll_gradient")
    assert roll["kind"] == "==" and abs(roll["value"] - value) < 1e-7
    if method == "slsqp" and value == 45.0:
        assert json.loads(json.dumps(optimise.result_report(res)))["converged"] is True  # plain JSON types


@pytest.mark.slow
def test_slsqp_finds_the_constrained_optimum_on_the_car(design, known, tmp_path):
    """On the car (the shared 2-mode program): with the roll-gradient bound below its value
    at the target's optimum, SLSQP ends where the roll gradient equals the bound (brentq on
    the forward model, 1e-4), converged, in at most 30 evaluations (the augmented
    Lagrangian took 1400-2400 on such points, docs/objectives.md)."""
    _, lam_star, path = known
    eps = _roll(design, lam_star - 0.03)
    study = _slsqp_study(path, tmp_path, "tight.toml")
    study = study._replace(constraints=tuple(c._replace(bound=eps) if c.spec.name == "roll_gradient" else c
                                             for c in study.constraints))
    res = optimise.optimise_study(study, design=design)
    root = scipy.optimize.brentq(lambda x: _roll(design, x) - eps, 0.3005, lam_star, xtol=1e-12)
    assert res.converged, res.message
    assert abs(res.optimum["lambda"] - root) < LAMBDA_TOL and res.evaluations <= 30


# ---- bad study files ----------------------------------------------------------------------------

GOOD = """
[study]
modes = 0
[[variables]]
path = "lambda"
lower = 0.3
upper = 0.7
[objective]
name = "understeer_gradient"
target = 0.1
"""


@pytest.mark.parametrize("old, new, match", [
    ('name = "understeer_gradient"', 'name = "understeer"',
     "objective.name = 'understeer' is not a known objective: allowed understeer_gradient, steering_sensitivity"),
    ("lower = 0.3\nupper = 0.7", "lower = 0.7\nupper = 0.3",
     "variables[0] has lower = 0.7, upper = 0.3: reversed or empty bounds, allowed lower < upper"),
    ("upper = 0.7", "upper = 0.7\ninitial = 0.9", "variables[0].initial = 0.9 is not allowed: strictly between"),
    ("upper = 0.7", "upper = 1.2", "has lambda values 0.3 to 1.2: allowed 0 < lambda < 1"),
    ("target = 0.1", 'target = 0.1\n[[constraints]]\nname = "chi"\n">=" = 0.6\n"<=" = 0.5',
     "constraints[0] is infeasible: chi >= 0.6 (constraints[0]) and <= 0.5 (constraints[0]) leave no value"),
    ("target = 0.1", 'target = 0.1\n[[constraints]]\nname = "chi"\n">=" = 0.6\n[[constraints]]\nname = "chi"\n'
     '"<=" = 0.5', "constraints[0] is infeasible: chi >= 0.6 (constraints[0]) and <= 0.5 (constraints[1])"),
    ("target = 0.1", 'target = 0.1\n[[constraints]]\nname = "chi"', 'constraints[0] needs a bound: "<=" = VALUE'),
    ("target = 0.1", 'target = 0.1\n[[constraints]]\nname = "chi"\n"==" = 0.45\n"<=" = 0.5',
     'constraints[0]."==" is not allowed beside "<=" or ">=" in one table: an equality stands alone'),
    ("target = 0.1", 'target = 0.1\n[[constraints]]\nname = "chi"\n">=" = 0.6\n[[constraints]]\nname = "chi"\n'
     '"==" = 0.5', "constraints[0] is infeasible: chi >= 0.6 (constraints[0]) and <= 0.5 (constraints[1])"),
    ("target = 0.1", 'target = 0.1\n[[constraints]]\nname = "chi"\n"==" = 0.4\n[[constraints]]\nname = "chi"\n'
     '"==" = 0.5', "constraints[1] is infeasible: chi >= 0.5 (constraints[1]) and <= 0.4 (constraints[0])"),
    ('name = "understeer_gradient"', 'name = "chassis_mass"', "is an objective of the chassis frame"),
    ("target = 0.1", "target = 0.1\nminimise = true", "needs exactly one of target = VALUE, minimise = true"),
    ("target = 0.1", "target = 0.1\nspeed = 3.0", "objective.speed is not a key of objective 'understeer_gradient'"),
    ("target = 0.1", 'target = 0.1\ncorner = "middle"', "objective.corner is not a key of objective"),
    ("target = 0.1", 'target = 0.1\n[[constraints]]\nname = "rear_steer_gradient"\ncorner = "front"\n"<=" = 1.0',
     "constraints[0].corner = 'front' is not allowed: one of rear_left, rear_right, rear"),
    ("target = 0.1", "target = 0.1\nscale = 0", "objective.scale = 0 is not allowed: a number > 0"),
    ("target = 0.1", 'target = 0.1\n[optimiser]\nmethod = "newton"',
     "optimiser.method = 'newton' is not allowed: one of lbfgs, adam"),
    ("target = 0.1", "target = 0.1\n[optimiser]\nsteps = 0", "optimiser.steps = 0 is not allowed: an integer from 1"),
    ("[study]", '[study]\nmodel = "analytic"', "study.model = 'analytic' is not allowed: 'car'"),
    ("modes = 0", "modes = 30", "study.modes = 30 is not allowed: an integer from 0 to 20"),
    ("[objective]", '[[variables]]\npath = "springs.spring_rate[0]"\nlower = 1.0\nupper = 2.0\n[objective]',
     "cannot be varied together with lambda"),
    ("[objective]", "[[variables]]\npath = 'coupling'\nlower = 0.1\nupper = 0.9\nstart = 1\n[objective]",
     "variables.start is not a known key: allowed keys of [variables] are path, name, units, lower, upper"),
    ("target = 0.1", 'target = 0.1\n[pareto]\nconstraint = "chi"\nvalues = [0.4, 0.5]',
     "pareto.constraint = 'chi' is not allowed: the name of exactly one bound of [[constraints]]"),
    ("target = 0.1", 'target = 0.1\n[[constraints]]\nname = "chi"\n">=" = 0.3\n"<=" = 0.6\n[pareto]\n'
     'constraint = "chi"\nvalues = [0.4, 0.5]', "the bounds: chi, chi"),
    ("target = 0.1", 'target = 0.1\n[[constraints]]\nname = "chi"\n"<=" = 0.6\n[pareto]\n'
     'constraint = "chi"\nvalues = [0.4, 0.5, 0.45]', "pareto.values = [0.4, 0.5, 0.45] is not allowed: strictly"),
    ("target = 0.1", 'target = 0.1\n[[constraints]]\nname = "chi"\n"<=" = 0.6\n[pareto]\n'
     'constraint = "chi"\nvalues = [0.4]\nsteps = 3', "pareto.steps is not a known key"),
])
def test_bad_study_files_are_refused_by_name(tmp_path, old, new, match):
    assert old in GOOD
    path = _write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(ParameterError) as info:
        optimise.load_optimisation_study(path)
    assert str(path) in str(info.value) and match in str(info.value), str(info.value)


def test_unknown_path_is_refused_on_the_car(tmp_path):
    """A path CarParams lacks, and a bound outside the car's range, are refused when the car
    is built (before anything compiles), naming the file and key."""
    bad = GOOD.replace('path = "lambda"', 'path = "arb_rate[0]"').replace("lower = 0.3\nupper = 0.7",
                                                                          "lower = 1.0\nupper = 20.0")
    path = _write(tmp_path, bad)
    with pytest.raises(ParameterError, match=r"variables\[0\]\.path = 'arb_rate\[0\]' is not allowed: .*arb_rate"):
        optimise.build_design(optimise.load_optimisation_study(path))
    bad = GOOD.replace('path = "lambda"', 'path = "arb_rates[0]"').replace("lower = 0.3", "lower = -1.0")
    path = _write(tmp_path, bad)
    with pytest.raises(ParameterError, match=r"variables\[0\] value -1.0 of 'arb_rates\[0\]' is out of range: "
                                             r"arb_rates .* must lie in \[0, inf\)"):
        optimise.build_design(optimise.load_optimisation_study(path))


def test_cli_refuses_a_bad_study(tmp_path):
    path = _write(tmp_path, GOOD.replace("lower = 0.3", "lower = 0.8"))
    result = CliRunner().invoke(app, ["optimise", str(path), "--json"])
    assert result.exit_code == 2 and "reversed or empty bounds" in result.output


def test_objective_library_lists_units_and_settings():
    """Every objective names its units and settings; the frame's are functions of a Frame."""
    for name, objective in optimise.OBJECTIVES.items():
        assert objective.units and objective.description and objective.function.__doc__, name
        assert {k for k, _ in optimise.objective_spec(name).settings} == set(objective.settings), name
    assert optimise.OBJECTIVES["understeer_gradient"].settings == {"ay_g": 0.05, "radius": 50.0}
    with pytest.raises(ParameterError, match="objective 'chassis_mass' is not known .an objective of the frame"):
        optimise.objective_spec("chassis_mass")


def test_frame_objectives_derivatives():
    """The frame's mass and torsional stiffness: forward-mode derivatives along the first
    section's wall thickness equal central differences (FE: assembly, static solve)."""
    import equinox as eqx

    import jaxveh.fe as fe

    frame = fe.load_frame()
    t0 = frame.sections[0].thickness

    def f(t):
        fr = eqx.tree_at(lambda x: x.sections[0].thickness, frame, t)
        return jnp.stack([optimise.chassis_mass(fr), optimise.torsional_stiffness(fr)])

    value, jvp = jax.jvp(f, (t0,), (jnp.ones_like(t0),))
    # step 1e-4 of the wall: the static solve's rounding (about 1e-11 of the stiffness)
    # over a 1e-6 step is already 1e-6 of the derivative; measured error at 1e-4: 7e-8
    h = 1e-4 * float(t0)
    fd = (f(t0 + h) - f(t0 - h)) / (2 * h)
    np.testing.assert_allclose(jvp, fd, rtol=1e-6)
    assert float(value[0]) > 0 and float(value[1]) > 0


def test_rear_steer_gradient_of_the_axle():
    """``corner = "rear"`` is the mean of both rear wheels' road-wheel angle gradients;
    a front corner is refused by name, in a study file too."""
    from types import SimpleNamespace

    from optimise._objectives import _rear_steer_gradient

    pad = SimpleNamespace(ok=jnp.array([True]), gradients={"road_wheel_angle": jnp.array([[9.0, 9.0, 0.01, -0.03]])})
    assert float(_rear_steer_gradient(pad, "rear")) == pytest.approx(-0.01 * GRAVITY, rel=1e-15)
    assert float(_rear_steer_gradient(pad, "rear_right")) == pytest.approx(-0.03 * GRAVITY, rel=1e-15)
    with pytest.raises(ParameterError, match="corner = 'front_left' is not allowed: rear_left, rear_right or rear"):
        _rear_steer_gradient(pad, "front_left")
    spec = optimise.objective_spec("rear_steer_gradient", {"corner": "rear"})
    assert dict(spec.settings)["corner"] == "rear"


def test_optimum_car_file_carries_hard_points_and_stiffness_multipliers(design, study_path, tmp_path):
    """The optimum's car file holds every changed value a car file can hold — a hard-point
    coordinate, a whole hard point, a mode's stiffness multiplier µ, a bar rate, the sprung
    mass, the tyre rate, a controller gain — in the file's units: read back by load_car it
    gives the optimum's parameters (1e-12); only the changed lines differ from the base
    file; a variable no car file holds is named in the header."""
    car = design.car
    changes = {"vehicle.hard_points_rear.points[7, 2]": 0.3191, "vehicle.hard_points_front.points[8, 0]": -0.0605,
               "vehicle.hard_points_front.points[8, 1]": 0.5412, "chassis.stiffness_scale[1]": 3.5,
               "arb_rates[0]": 25.0, "vehicle.sprung.mass": 231.5, "vehicle.tyre.kz": 161000.0, "pid.kp": 280.0,
               "springs.bump_stop_rate[0]": 1.5e5}
    optimum_car = with_params(car, changes)
    study = optimise.load_optimisation_study(study_path)
    variables = tuple(optimise.DesignVariable(name=f"v{i}", path=p, lower=-1e9, upper=1e9, initial=0.0)
                      for i, p in enumerate(changes))
    study = study._replace(variables=variables)
    result = optimise.OptimisationResult(study=study, optimum={v.name: 0.0 for v in variables}, objective=0.0,
                                         values={}, constraints=[], converged=True, message="", iterations=0,
                                         evaluations=0, history=[], car=optimum_car, failed=False, wall_s=0.0)
    text = optimise.optimum_car_file(result)
    path = tmp_path / "optimum_car.toml"
    path.write_text(text)
    reloaded = load_car(path, modes=MODES)
    for p in changes:
        if not p.startswith("springs"):
            np.testing.assert_allclose(np.asarray(optimise.get_leaf(reloaded.params, p)), np.asarray(changes[p]),
                                       rtol=1e-12, err_msg=p)
    assert float(reloaded.params.chassis.stiffness_scale[0]) == 1.0
    assert "# Not in a car file (set them with --param): springs.bump_stop_rate[0] = 150000" in text
    base = (Path(__file__).parents[1] / "jaxveh" / "params" / "data" / "car.toml").read_text().splitlines()
    new = text.splitlines()[3:]
    diff = list(difflib.ndiff(base, new))
    changed = [line[2:] for line in diff if line.startswith("+ ")]
    assert sum(line.startswith("- ") for line in diff) == 6 and len(changed) == 7  # stiffness_scale is a new line
    assert set(optimise.changed_car_values(result)) == {
        "vehicle.hard_points_rear.points[7]", "vehicle.hard_points_front.points[8]", "chassis.stiffness_scale",
        "arb_rates[0]", "vehicle.sprung.mass", "vehicle.tyre.kz", "pid.kp"}
    assert any(line.startswith("L = [-61.0, 248.8, 319.1]") for line in changed)
    assert any(line.startswith("M = [-60.5, 541.2, 344.0]") for line in changed)
    assert "stiffness_scale = [1.0, 3.5]" in changed
