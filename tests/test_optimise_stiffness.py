"""How stiff is stiff enough (optimise._stiffness, issue 14 study (a)): the search against a
model with a closed-form answer, the study files' refusals by name, and on the 2-mode car
(slow): the rigid reference and the loaded car against jaxveh.analysis's own load transfer
and skid-pad programs, the deviation's 1 / µ decay of a stiff mode, the answer's bracket
checked by fresh evaluations, and ``jaxveh optimise --json`` on a requirement study.

The synthetic model: quantity q of design scale µ at λ_j is ``ref_jq (1 + Σ_i a_ijq / µ_i)``,
so mode i alone (the others frozen) deviates by ``max_jq a_ijq / µ_i``, its minimum is
``max_jq a_ijq / tol`` exactly, and with every mode at its minimum and a common factor s
the deviation is ``max_jq Σ_i a_ijq / (s µ_min,i)``, so s follows in closed form too.
"""

import json
import math
import re
import textwrap

import numpy as np
import pytest
from typer.testing import CliRunner

import optimise
from jaxveh import GRAVITY, ParameterError
from jaxveh.analysis import FREEZE, chi_by_modes
from jaxveh.cli import app
from jaxveh.manoeuvre import skid_pad
from jaxveh.vehicle import load_car

TOL = 0.02
LAMBDAS = (0.3, 0.5, 0.7)
#: a_ijq of the synthetic model: 3 modes x 3 λ x 2 quantities (mode 3 tiny: within the
#: tolerance over the whole scan).
A = np.array([
    [[0.30, 0.10], [0.20, 0.05], [0.10, 0.40]],
    [[0.05, 0.02], [0.08, 0.01], [0.02, 0.03]],
    [[1e-4, 2e-4], [1e-4, 1e-4], [3e-4, 1e-4]],
])
REF = np.array([[0.3, -0.1], [0.5, -0.1], [0.7, -0.12]])


def _synthetic(a=A, base=None):
    base = np.ones(a.shape[0]) if base is None else base
    calls = []

    def evaluate(scale):
        calls.append(np.array(scale))
        mu = np.asarray(scale) / base
        return REF * (1.0 + np.einsum("i,ijq->jq", 1.0 / mu, a))

    return optimise.Handling(car=None, evaluate=evaluate, frequencies_hz=np.array([30.0, 45.0, 60.0]),
                             base_scale=base), calls


def _study(**kw):
    return optimise.StiffnessStudy(name="s", quantities=(optimise.objective_spec("chi"),
                                                         optimise.objective_spec("understeer_gradient")),
                                   tolerance=TOL, lambdas=LAMBDAS, mu=(0.1, 1.0, 10.0, 100.0, 1000.0), rtol=1e-4,
                                   modes=3, **kw)


def test_search_finds_the_closed_form_minima_and_common_factor():
    h, _ = _synthetic()
    result = optimise.stiffness_requirement(_study(), handling=h)
    worst = A.max(axis=(1, 2))
    for m, w in zip(result.modes[:2], worst[:2]):
        assert m.status == "found"
        exact = w / TOL
        # the answer is the bracket's upper (stiff-enough) end, within rtol above the exact minimum
        assert exact <= m.mu_min <= exact * (1.0 + 1e-4)
        assert m.frequency_hz == pytest.approx(h.frequencies_hz[m.mode - 1] * math.sqrt(m.mu_min), rel=1e-12)
    # mode 1's worst: a = 0.40 at λ = 0.7 on the second quantity
    assert (result.modes[0].quantity, result.modes[0].lam) == ("understeer_gradient", 0.7)
    assert (result.modes[1].quantity, result.modes[1].lam) == ("chi", 0.5)
    third = result.modes[2]
    assert third.status == "below_range" and third.mu_min == 0.1
    # all modes at their minima exceed the tolerance (the effects add); the common factor is
    # max_jq sum_i a_ijq / mu_min,i / tol
    mu_min = np.array([m.mu_min for m in result.modes])
    exact_factor = np.max(np.einsum("i,ijq->jq", 1.0 / mu_min, A)) / TOL
    assert np.max(result.joint_at_minima) > TOL
    assert exact_factor <= result.factor <= exact_factor * (1.0 + 1e-4)
    assert np.max(result.joint_deviation) <= TOL
    np.testing.assert_allclose(result.joint_mu, mu_min * result.factor, rtol=1e-12)
    np.testing.assert_allclose(result.reference, REF * (1.0 + A.sum(axis=0) / FREEZE), rtol=1e-15)


def test_multipliers_are_relative_to_the_cars_own():
    base = np.array([2.0, 0.5, 1.0])
    h, calls = _synthetic(base=base)
    result = optimise.stiffness_requirement(_study(), handling=h)
    np.testing.assert_allclose(calls[0], base * FREEZE)   # the rigid reference
    np.testing.assert_allclose(calls[1], base)             # the car as loaded
    assert result.modes[0].mu_min == pytest.approx(A[0].max() / TOL, rel=2e-4)


def test_a_mode_never_stiff_enough_and_a_failed_design(tmp_path):
    a = A.copy()
    a[1] *= 1e5                       # mode 2 outside the tolerance even at µ = 1000
    h, _ = _synthetic(a)
    failing = h.evaluate

    def evaluate(scale):              # mode 1 at µ <= 1: its steady state fails (NaN)
        out = failing(scale)
        return np.full_like(out, np.nan) if scale[0] <= 1.0 else out

    result = optimise.stiffness_requirement(_study(), handling=h._replace(evaluate=evaluate))
    assert result.modes[1].status == "above_range" and result.modes[1].mu_min is None
    assert result.modes[1].frequency_hz is None
    assert result.factor is None and result.joint_mu is None
    first = result.modes[0]
    assert np.all(np.isinf(first.scan[:2]))            # the failed designs count as outside
    assert first.status == "found" and first.mu_min == pytest.approx(A[0].max() / TOL, rel=2e-4)
    report = optimise.stiffness_report(result)
    assert report["per_mode"][0]["scan_worst_deviation"]["chi"][:2] == [None, None]
    json.dumps(report, allow_nan=False)
    files = optimise.write_stiffness_outputs(result, tmp_path)     # the figure with a mode never stiff enough
    assert json.loads(open(files["json"]).read())["per_mode"][1]["status"] == "above_range"


def test_failed_reference_is_reported():
    h, _ = _synthetic()
    bad = h._replace(evaluate=lambda scale: np.full((3, 2), np.nan))
    with pytest.raises(RuntimeError, match="rigid reference's steady state failed at lambda"):
        optimise.stiffness_requirement(_study(), handling=bad)


def test_report_and_figure(tmp_path):
    h, _ = _synthetic()
    result = optimise.stiffness_requirement(_study(out=str(tmp_path)), handling=h)
    files = optimise.write_stiffness_outputs(result)
    report = json.loads(open(files["json"]).read())
    assert [m["status"] for m in report["per_mode"]] == ["found", "found", "below_range"]
    assert report["joint"]["factor"] == pytest.approx(result.factor)
    assert report["quantities"][0] == {"name": "chi", "units": "1", "ay_g": [0.05, 0.1], "radius": 50.0}
    assert open(files["png"], "rb").read(8) == b"\x89PNG\r\n\x1a\n"


GOOD = """
[study]
modes = 2
[[quantities]]
name = "chi"
[requirement]
tolerance = 0.02
lambda = [0.3, 0.7]
mu = [0.1, 1.0, 10.0]
"""


def _write(tmp_path, text, name="s.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_loads_a_good_file_with_defaults(tmp_path):
    s = optimise.load_stiffness_study(_write(tmp_path, GOOD))
    assert (s.name, s.modes, s.lambdas, s.mu) == ("s", 2, (0.3, 0.7), (0.1, 1.0, 10.0))
    assert s.rtol == optimise._stiffness.RTOL
    assert [q.name for q in s.quantities] == ["chi"]
    assert optimise.is_stiffness_study(_write(tmp_path, GOOD))
    shipped = optimise.load_stiffness_study("experiments/studies/stiff_enough.toml")
    assert [q.name for q in shipped.quantities] == ["chi", "understeer_gradient"]
    assert shipped.lambdas == (0.3, 0.4, 0.5, 0.6, 0.7) and shipped.mu[0] == 0.1 and shipped.mu[-1] == 1e4
    assert not optimise.is_stiffness_study("experiments/studies/roll_balance.toml")


@pytest.mark.parametrize("change, key", [
    (("tolerance = 0.02", "tolerance = 1.5"), "requirement.tolerance"),
    (("tolerance = 0.02", "tolerance = 0.02\nspeed = 3"), "requirement.speed"),
    (("lambda = [0.3, 0.7]", "lambda = [0.7, 0.3]"), "requirement.lambda"),
    (("lambda = [0.3, 0.7]", "lambda = [0.0, 0.7]"), "requirement.lambda"),
    (("mu = [0.1, 1.0, 10.0]", "mu = [1.0]"), "requirement.mu"),
    (("mu = [0.1, 1.0, 10.0]", "mu = [0.1, -1.0]"), "requirement.mu"),
    (("mu = [0.1, 1.0, 10.0]", "mu = [0.1, 1.0]\nmu_range = [0.1, 10.0, 3]"), "requirement.mu"),
    (("mu = [0.1, 1.0, 10.0]", "mu_range = [10.0, 0.1, 3]"), "requirement.mu_range"),
    (("mu = [0.1, 1.0, 10.0]", "mu_range = [0.1, 10.0, 2.5]"), "requirement.mu_range"),
    (("mu = [0.1, 1.0, 10.0]", "rtol = 0.0"), "requirement.rtol"),
    (("modes = 2", "modes = 0"), "study.modes"),
    (("modes = 2", "modes = 2\nvehicle = 'missing.toml'"), "study.vehicle"),
    (("modes = 2", "modes = 2\nmodel = 'analytic'"), "study.model"),
    (('name = "chi"', 'name = "first_mode_frequency"'), "quantities[0].name"),
    (('name = "chi"', 'name = "chassis_mass"'), "quantities[0].name"),
    (('name = "chi"', 'name = "drift"'), "quantities[0].name"),
    (('name = "chi"', 'name = "chi"\nspeed_kmh = 50.0'), "quantities[0].speed_kmh"),
    (('name = "chi"', 'name = "chi"\n[[quantities]]\nname = "chi"'), "quantities[1]"),
    (("[requirement]", "[requirement]\n[optimiser]"), "file.optimiser"),
])
def test_bad_study_files_are_refused_by_name(tmp_path, change, key):
    path = _write(tmp_path, GOOD.replace(*change))
    with pytest.raises(ParameterError, match=r"s\.toml: " + re.escape(key)):
        optimise.load_stiffness_study(path)


@pytest.mark.parametrize("change, key", [
    ({"tolerance": 0.0}, "requirement.tolerance"),
    ({"rtol": 2.0}, "requirement.rtol"),
    ({"lambdas": (0.5, 0.4)}, "requirement.lambda"),
    ({"mu": (1.0,)}, "requirement.mu"),
    ({"mu": (1.0, -2.0)}, "requirement.mu"),
    ({"modes": 0}, "study.modes"),
    ({"quantities": ()}, "quantities"),
    ({"quantities": (optimise.objective_spec("first_mode_frequency"),)}, "quantities[0].name"),
])
def test_a_study_built_in_python_is_checked(change, key):
    """The Python API refuses what the file loader refuses, by name, before any evaluation."""
    h, calls = _synthetic()
    with pytest.raises(ParameterError, match=r"study: " + re.escape(key)):
        optimise.stiffness_requirement(_study()._replace(**change), handling=h)
    assert calls == []


def test_cli_refuses_a_bad_requirement_study(tmp_path):
    path = _write(tmp_path, GOOD.replace("tolerance = 0.02", "tolerance = -1"))
    res = CliRunner().invoke(app, ["optimise", str(path), "--json"])
    assert res.exit_code == 2 and "requirement.tolerance" in res.output


# ---- on the 2-mode car ------------------------------------------------------------------------

#: The car tests' study: λ = 0.4 and the car's own λ (its bars as loaded), a short scan.
MODES = 2
CAR_STUDY = """
[study]
name = "car"
modes = 2
[[quantities]]
name = "chi"
[[quantities]]
name = "understeer_gradient"
[requirement]
tolerance = 0.02
lambda = [0.4, {lam!r}]
mu = [0.3, 3.0, 30.0, 300.0]
rtol = 0.05
"""


@pytest.fixture(scope="module")
def car_run(tmp_path_factory):
    car = load_car(modes=MODES)
    rates = optimise.roll_rate_coefficients(car)
    k_front = rates.springs_front + rates.bar_front * float(car.params.arb_rates[0])
    k_rear = rates.springs_rear + rates.bar_rear * float(car.params.arb_rates[1])
    lam = float(k_front / (k_front + k_rear))
    folder = tmp_path_factory.mktemp("stiff")
    path = folder / "car.toml"
    path.write_text(CAR_STUDY.format(lam=lam))
    study = optimise.load_stiffness_study(path, out=folder / "out")
    handling = optimise.build_handling(study)
    result = optimise.stiffness_requirement(study, handling=handling)
    return car, lam, study, handling, result, path


@pytest.mark.slow
def test_reference_and_car_equal_the_librarys_programs(car_run):
    """At the car's own λ the bars are the loaded ones: the frozen reference's χ equals the
    rigid entry of ``chi_by_modes`` and the loaded car's χ its 2-mode entry (another
    program: load_transfer_batch); the loaded car's ku equals ``skid_pad``'s."""
    car, lam, study, h, result, _ = car_run
    chi = np.asarray(chi_by_modes(MODES))
    assert result.reference[1, 0] == pytest.approx(chi[0], abs=1e-7)
    assert result.nominal[1, 0] == pytest.approx(chi[MODES], abs=1e-9)
    ku = float(skid_pad(car, 50.0, np.array([0.05 * GRAVITY])).understeer_gradient[0])
    assert result.nominal[1, 1] == pytest.approx(ku, rel=1e-6)
    # the flexible car differs from the rigid one by more than the tolerance (else no question)
    assert np.max(optimise.relative_deviation(result.nominal, result.reference)) > study.tolerance


@pytest.mark.slow
def test_deviation_of_a_stiff_mode_falls_as_one_over_mu(car_run):
    """Deflection under a given load falls as 1 / µ: between µ = 30 and 300 each mode's
    deviation from the rigid car falls tenfold (within 3 %)."""
    *_, result, _ = car_run
    for m in result.modes:
        d30, d300 = np.max(m.scan[2], axis=0), np.max(m.scan[3], axis=0)
        np.testing.assert_allclose(d30 / d300, 10.0, rtol=0.03)


@pytest.mark.slow
def test_answer_is_bracketed_by_fresh_evaluations(car_run):
    """Each found minimum is within the tolerance and its rtol-lower neighbour is not,
    evaluated afresh; so is the joint answer."""
    _, _, study, h, result, _ = car_run
    ref = result.reference
    for m in result.modes:
        if m.status != "found":
            continue
        scale = h.base_scale * FREEZE
        scale[m.mode - 1] = h.base_scale[m.mode - 1] * m.mu_min
        assert np.max(optimise.relative_deviation(h.evaluate(scale), ref)) <= study.tolerance
        scale[m.mode - 1] /= 1.0 + 2.0 * study.rtol
        assert np.max(optimise.relative_deviation(h.evaluate(scale), ref)) > study.tolerance
    assert any(m.status == "found" for m in result.modes)
    if result.joint_mu is not None:
        assert np.max(optimise.relative_deviation(h.evaluate(h.base_scale * result.joint_mu), ref)) <= study.tolerance


@pytest.mark.slow
def test_cli_json(car_run, tmp_path):
    *_, result, path = car_run
    res = CliRunner().invoke(app, ["optimise", str(path), "--out", str(tmp_path), "--json"])
    assert res.exit_code == 0, res.output
    report = json.loads(res.output)
    assert [m["mu_min"] for m in report["per_mode"]] == [m.mu_min for m in result.modes]
    assert set(report["files"]) == {"json", "png"} and (tmp_path / "car.png").is_file()
