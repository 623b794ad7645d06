"""Lateral load transfer of the chapter-6 car (section 7.1.2, Fig. 7.2) and its consistency
with chapter 3 (eqs. 3.2-3.6), jaxveh.analysis; the ``jaxveh vehicle lltd`` command.

Three compiled programs: the rigid car's load-transfer curve (shared with the CLI test),
one vmapped call over thirteen designs of the 2-mode car, and the gradient of χ with respect
to the 2-mode car's modal stiffness multipliers.
"""

import json
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from typer.testing import CliRunner

from jaxveh import analysis as an, analytic
from jaxveh._core import GRAVITY, ParameterError
from jaxveh.cli import app
from jaxveh.tyre import mirror_symmetric
from jaxveh.vehicle import car_rates, load_car

#: Rigid car, χ at low ay (incremental, 0.05-0.1 g, R = 50 m) vs eq. (3.4) with the car's own
#: parameters (chapter3_parameters): measured 0.5095 vs 0.4902, a gap of 0.0193 (3.9 %).
#: 0.0024 of it is the roll-gravity term and the wheels' gyroscopic roll moment, which
#: chapter 3 neglects by assumption (closed form: test_total_transfer_matches_extended_
#: closed_form). The rest is the split between the axles: the car behaves as if its roll
#: centres were 47 / 27 mm instead of the kinematic 54 / 53 mm (the total is unaffected);
#: not explained yet, see docs/analysis.md. 0.025 is the thesis's own level of agreement
#: between its multibody car and eq. 3.6 away from the best λ (Fig. 7.2b), not a derived
#: bound: the measured gap is stated here so that a change that widens it shows.
CHI_CHAPTER3_ATOL = 0.025
CHI_CHAPTER3_MEASURED_GAP = 0.0193
#: Total per-ay load transfer (tF ΔFzF + tR ΔFzR) vs the closed form with the two neglected
#: terms added: measured 0.3 %; tyre aligning moments and compliance are not in it (0.5 %).
TOTAL_RTOL = 5e-3
#: eq. (3.5) with equal tracks and the library's closed form eq. (3.6): algebra only.
ALGEBRA_RTOL = 1e-12
#: Central differences of χ in µ (step 1e-3 on the multipliers): truncation O(h^2) ~ 1e-7
#: relative, Newton's tolerance (1e-11 relative) divided by h ~ 1e-8: 1e-5 relative.
GRAD_RTOL = 1e-5
FD_STEP = 1e-3
#: µ = 1e4 on both modes vs the rigid car: the modal compliance left is 1e-4 of the flexible
#: car's effect (|χ_flex - χ_rigid| ~ 0.01), so 1e-5; the rigid car's chassis body and
#: the modal one differ by nothing else.
STIFF_ATOL = 1e-5
#: Left and right turns on mirror-symmetric tyres (jaxveh.tyre.mirror_symmetric; the rigid
#: chassis is symmetric): Newton's tolerance on loads (~1e-9 N) over increments of ~18 N.
SYMMETRY_ATOL = 1e-6
#: ... and on the shipped tyre, whose aligning moment is asymmetric (docs/tyre.md): left and
#: right χ differ by a measured 3.8e-4.
SHIPPED_TYRE_SYMMETRY_ATOL = 1e-3
#: Front transfer's slope from the first point, spread over 0.05-1.2 g: measured 4.5 % on
#: the rigid car (the slope falls steadily as the skid-pad speed, and with it the aero
#: load, rises with ay); 5 % states "linear" (section 7.1.2) at that level.
LINEARITY_RTOL = 0.05

runner = CliRunner()


@pytest.fixture(scope="module")
def rigid():
    return load_car(modes=0)


@pytest.fixture(scope="module")
def rigid_lt(rigid):
    return an.load_transfer(rigid)


@pytest.fixture(scope="module")
def symmetric_lt(rigid):
    """The rigid car on mirror-symmetric tyres (same compiled program as ``rigid_lt``)."""
    car = eqx.tree_at(lambda c: c.params.tyres, rigid, mirror_symmetric(rigid.params.tyres))
    return an.load_transfer(car)


@pytest.fixture(scope="module")
def flex():
    return load_car(modes=2)


def _set_scale(params, scale):
    return eqx.tree_at(lambda p: p.chassis.stiffness_scale, params, jnp.asarray(scale, jnp.float64))


MUS = (0.1, 1.0, 10.0)


@pytest.fixture(scope="module")
def flex_batch(flex):
    """One vmapped call: [the car, both modes at µ = 1e4, mode i at 1 ± h (i = 0, 1),
    mode i at each of MUS]."""
    p = flex.params
    designs = [p, _set_scale(p, [1e4, 1e4])]
    for i in range(2):
        for s in (1.0 + FD_STEP, 1.0 - FD_STEP):
            designs.append(_set_scale(p, np.where(np.arange(2) == i, s, 1.0)))
    stack = jax.tree.map(lambda *x: jnp.stack(x), *designs)
    stack = jax.tree.map(lambda a, b: jnp.concatenate([a, b]), stack, an.mode_stiffness_designs(flex, MUS))
    return an.load_transfer_batch(flex, stack, an.LOW_AY_PAIR_G)


# ---- chapter 3 ------------------------------------------------------------------------------


def test_mapping_values(rigid):
    """The mapping reproduces the Appendix B data and the car's own rates."""
    p = an.chapter3_parameters(rigid)
    rates = car_rates(rigid)
    assert float(p.kF) == pytest.approx(float(rates["front"].roll_stiffness), rel=1e-14)
    assert float(p.kR) == pytest.approx(float(rates["rear"].roll_stiffness), rel=1e-14)
    # Appendix A's 205 / 175 N m/deg, which the car's springs and bars were chosen to match
    assert float(p.kF) * math.pi / 180 == pytest.approx(205.0, abs=0.5)
    assert float(p.kR) * math.pi / 180 == pytest.approx(175.0, abs=0.5)
    assert float(p.m) == pytest.approx(225.0 + 2 * 14.0 + 2 * 18.5, rel=1e-14)
    # the whole car's c.g. at h_cg = 295 mm above the design ground, the road at rest lower
    h = (float(p.ms) * float(p.hs) + float(p.muF) * float(p.huF) + float(p.muR) * float(p.huR)) / float(p.m)
    assert h == pytest.approx(0.295 - float(an.static_sink(rigid)), abs=1e-12)
    assert float(p.as_ + p.bs) == pytest.approx(1.7, abs=1e-12)
    # front-view instant centres of the Appendix B wishbones, by hand: lower line (249.7,
    # 145)-(585.6, 140), upper (259.75, 345)-(560.9, 380.3) mm meet at y = -1255.3, z = 167.4;
    # roll centres 54.0 / 52.6 mm above the road at rest
    lower = np.polyfit([249.7, 585.6], [145.0, 140.0], 1)
    upper = np.polyfit([259.75, 560.9], [345.0, 380.3], 1)
    y_ic = (upper[1] - lower[1]) / (lower[0] - upper[0])
    z_ic = np.polyval(lower, y_ic)
    sink = 1e3 * float(an.static_sink(rigid))
    for z, half_track in zip(an.roll_centre_heights(rigid), (630.0, 605.0)):
        expected = (z_ic - sink) * half_track / (half_track - y_ic)  # road at z = +sink, design frame
        assert 1e3 * float(z) == pytest.approx(expected, abs=1e-9)


def test_equation_3_5_is_library_equation_3_6(rigid):
    """With equal tracks, eq. (3.5) here and the library's closed form eq. (3.6) agree, rigid
    (eq. 3.3) and flexible, for several λ."""
    p = an.chapter3_parameters(rigid)
    p = eqx.tree_at(lambda q: q.tR, p, p.tF)
    for lam in (0.3, 0.54, 0.7):
        q = an.with_lambda(p, lam)
        v = an.analytic_vehicle(q)
        assert float(an.chapter3_chi(q, flexible=True)) == pytest.approx(float(analytic.chi(v)), rel=ALGEBRA_RTOL)
        assert float(an.chapter3_chi(q)) == pytest.approx(float(analytic.chi_rigid(v)), rel=ALGEBRA_RTOL)


def test_chi_low_ay_agrees_with_chapter_3(rigid, rigid_lt):
    """Issue 12: χ at low ay of the rigid car vs eqs. (3.2)-(3.4) for the car's own roll
    stiffnesses and geometry (tolerance: CHI_CHAPTER3_ATOL)."""
    assert bool(jnp.all(rigid_lt.ok))
    p = an.chapter3_parameters(rigid)
    chi_eq = float(an.chapter3_chi(p))
    chi_mb = float(rigid_lt.chi_low_ay)
    assert abs(chi_mb - chi_eq) < CHI_CHAPTER3_ATOL, (chi_mb, chi_eq)
    assert chi_mb - chi_eq == pytest.approx(CHI_CHAPTER3_MEASURED_GAP, abs=1e-4)  # the documented number


def test_total_transfer_matches_extended_closed_form(rigid, rigid_lt):
    """tF ΔFzF + tR ΔFzR per ay (increments between the two low ay) equals chapter 3's total
    moment plus the two terms it neglects: the roll-gravity term (the sprung weight moved sideways by the roll angle,
    factor 1 / (1 - ms g ds / K)) and the four wheels' gyroscopic roll moment
    (J_w ω_spin ω = J_w ay / r per wheel, r the loaded radius)."""
    p = an.chapter3_parameters(rigid)
    v = rigid.params.vehicle
    l_s = p.as_ + p.bs
    msF, msR = p.ms * p.bs / l_s, p.ms * p.as_ / l_s
    sprung = msF * (p.hs - p.zF) + msR * (p.hs - p.zR)
    gravity = sprung * GRAVITY / (p.kF + p.kR)
    r_loaded = p.huF  # the wheel centre's height above the road at rest
    gyro = 2 * (v.unsprung_front.wheel_spin_inertia + v.unsprung_rear.wheel_spin_inertia) / r_loaded
    total = sprung / (1.0 - gravity) + gyro + p.zF * msF + p.zR * msR + p.huF * p.muF + p.huR * p.muR
    d_ay = float(rigid_lt.ay[1] - rigid_lt.ay[0])
    d_front, d_rear = (float(x[1] - x[0]) for x in (rigid_lt.front, rigid_lt.rear))
    measured = (d_front * float(p.tF) + d_rear * float(p.tR)) / d_ay
    assert measured == pytest.approx(float(total), rel=TOTAL_RTOL)
    # without the two terms the gap is several times larger: they are what is missing
    plain = sprung + p.zF * msF + p.zR * msR + p.huF * p.muF + p.huR * p.muR
    assert abs(measured / float(plain) - 1.0) > 5 * TOTAL_RTOL


def test_load_transfer_is_linear_in_ay(rigid_lt):
    """Section 7.1.2: a linear relation between load transfer and ay (front transfer's
    slope from the first point within LINEARITY_RTOL up to 1.2 g on the rigid car)."""
    assert bool(jnp.all(rigid_lt.ok))
    front, ay = np.asarray(rigid_lt.front), np.asarray(rigid_lt.ay)
    slope = (front[1:] - front[0]) / (ay[1:] - ay[0])
    assert np.ptp(slope) / np.mean(slope) < LINEARITY_RTOL


def _left_right(lt):
    """χ from the increments of the right-less-left load difference between the two low ay,
    turning left and turning right."""
    dl = (lt.diff_left[1] - lt.diff_left[0]) / 2.0
    dr = -(lt.diff_right[1] - lt.diff_right[0]) / 2.0
    return float(dl[0] / jnp.sum(dl)), float(dr[0] / jnp.sum(dr))


def test_left_and_right_turns_give_the_same_chi(rigid_lt, symmetric_lt):
    """On mirror-symmetric tyres a right turn is a left one mirrored: the same χ, and the
    load differences themselves mirror (no static offsets); on the shipped tyre nearly so."""
    chi_left, chi_right = _left_right(symmetric_lt)
    assert abs(chi_left - chi_right) < SYMMETRY_ATOL
    assert abs(chi_left - float(symmetric_lt.chi_low_ay)) < SYMMETRY_ATOL
    np.testing.assert_allclose(symmetric_lt.diff_left, -symmetric_lt.diff_right, atol=1e-6)
    chi_left, chi_right = _left_right(rigid_lt)
    assert abs(chi_left - chi_right) < SHIPPED_TYRE_SYMMETRY_ATOL
    assert abs(float(symmetric_lt.chi_low_ay) - float(rigid_lt.chi_low_ay)) < SHIPPED_TYRE_SYMMETRY_ATOL


# ---- the flexible car -----------------------------------------------------------------------


@pytest.mark.slow
def test_stiff_modes_give_the_rigid_chi(flex_batch, rigid_lt):
    assert bool(jnp.all(flex_batch.ok))
    chi = np.asarray(flex_batch.chi_low_ay)
    assert abs(chi[1] - float(rigid_lt.chi_low_ay)) < STIFF_ATOL
    # and the flexible car's χ differs from the rigid one's (the effect exists)
    assert abs(chi[0] - float(rigid_lt.chi_low_ay)) > 100 * STIFF_ATOL


@pytest.mark.slow
def test_chi_vs_single_mode_stiffness(flex, flex_batch):
    """χ against each mode's multiplier µ (Fig. 7.2d): at µ = 1 the car's own χ; monotone in
    µ; the car's modes through the single-design call."""
    chi = np.asarray(flex_batch.chi_low_ay[6:]).reshape(2, len(MUS))
    base = float(flex_batch.chi_low_ay[0])
    np.testing.assert_allclose(chi[:, 1], base, atol=1e-12)
    for row in chi:
        d = np.diff(row)
        assert np.all(d > 0) or np.all(d < 0)


@pytest.mark.slow
def test_gradient_vs_central_differences(flex, flex_batch):
    grad = np.asarray(an.chi_mode_stiffness_gradient(flex))
    chi = np.asarray(flex_batch.chi_low_ay)
    fd = np.asarray([(chi[2 + 2 * i] - chi[3 + 2 * i]) / (2 * FD_STEP) for i in range(2)])
    np.testing.assert_allclose(grad, fd, rtol=GRAD_RTOL, atol=1e-9)
    assert np.max(np.abs(grad)) > 1e-4  # the first torsion mode matters


# ---- the anti-roll-bar mapping and bad input --------------------------------------------------


def test_arb_rates_give_lambda(rigid):
    lams = jnp.asarray([0.2, 0.377, 0.45, 0.54, 0.6, 0.8])
    stack = an.lambda_designs(rigid, lams)
    k0 = sum(float(r.roll_stiffness) for r in car_rates(rigid).values())
    for i, lam in enumerate(np.asarray(lams)):
        car = eqx.tree_at(lambda c: c.params, rigid, jax.tree.map(lambda x, i=i: x[i], stack))
        rates = car_rates(car)
        kF, kR = float(rates["front"].roll_stiffness), float(rates["rear"].roll_stiffness)
        assert kF / (kF + kR) == pytest.approx(lam, abs=1e-12)
        assert float(jnp.min(car.params.arb_rates)) >= 0.0
        if 0.38 < lam < 0.62:  # both bars > 0: the total is kept
            assert kF + kR == pytest.approx(k0, rel=1e-12)
    # the car's own λ gives back the car's own bars
    lam0 = float(an.chapter3_parameters(rigid, 1.0).lam)
    np.testing.assert_allclose(an.arb_rates_for_distribution(rigid, lam0), rigid.params.arb_rates, rtol=1e-10)


def test_bad_input_named_errors(rigid):
    with pytest.raises(ParameterError, match=r"lam = 1\.2 is out of range: allowed 0 < lam < 1"):
        an.arb_rates_for_distribution(rigid, 1.2)
    with pytest.raises(ParameterError, match=r"ay_g = \[-0\.1\] is out of range: allowed .* > 0 \(g\)"):
        an.load_transfer(rigid, (-0.1,))
    with pytest.raises(ParameterError, match=r"radius = 0\.0 is out of range: allowed > 0 \(m\)"):
        an.load_transfer(rigid, radius=0.0)
    with pytest.raises(ParameterError, match=r"rigid chassis \(modes = 0\): a modal stiffness multiplier"):
        an.mode_stiffness_designs(rigid, (1.0,))
    with pytest.raises(ParameterError, match=r"torsional_stiffness = -1\.0 is out of range: allowed > 0"):
        an.chapter3_parameters(rigid, -1.0)
    with pytest.raises(ParameterError, match=r"max_modes = 30 is out of range: allowed integers 0 to 20"):
        an.chi_vs_modes(30)
    bad = eqx.tree_at(lambda c: c.params.arb_rates, rigid, jnp.asarray([-1.0, 1.0]))
    with pytest.raises(ParameterError, match=r"arb_rates"):
        an.load_transfer(bad)


def test_bad_mu_named_error(flex):
    with pytest.raises(ParameterError, match=r"mu = \[0\.0\] is out of range: allowed finite multipliers > 0"):
        an.mode_stiffness_designs(flex, (0.0,))


# ---- CLI ------------------------------------------------------------------------------------


def test_cli_lltd_json(rigid_lt, tmp_path):
    result = runner.invoke(app, ["vehicle", "lltd", "--rigid", "--json", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)
    assert report["chi_low_ay"] == pytest.approx(float(rigid_lt.chi_low_ay), abs=1e-12)
    assert report["chassis"] == "rigid"
    assert abs(report["chi_low_ay"] - report["chi_eq_3_4_rigid"]) < CHI_CHAPTER3_ATOL
    assert report["curve"]["ay_g"] == list(an.AY_GRID_G)
    assert len(report["curve"]["front_n"]) == len(an.AY_GRID_G)
    assert (tmp_path / "lltd.json").is_file() and (tmp_path / "lltd.csv").is_file()


def test_cli_lltd_bad_radius():
    result = runner.invoke(app, ["vehicle", "lltd", "--rigid", "--radius", "-5"])
    assert result.exit_code == 2
    assert "radius = -5.0 is out of range: allowed > 0 (m)" in result.output


# ---- χ against the number of modes (one vmapped call) ------------------------------------------


def test_modal_truncation_keeps_the_first_modes():
    """What `chi_by_modes` relies on: the first k modes of a larger car are the k-mode car's
    (shapes at every point, stiffness, damping)."""
    one, three = load_car(modes=1).params.chassis, load_car(modes=3).params.chassis
    for a, b in ((three.point_phi_translation[..., :1], one.point_phi_translation),
                 (three.point_phi_rotation[..., :1], one.point_phi_rotation),
                 (three.frequencies_hz[:1], one.frequencies_hz), (three.damping_ratios()[:1], one.damping_ratios())):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12 * float(np.max(np.abs(b))))


@pytest.fixture(scope="module")
def chi_by_modes():
    return np.asarray(an.chi_by_modes(2))


@pytest.mark.slow
def test_chi_by_modes_ends_at_the_rigid_and_the_full_car(chi_by_modes, rigid_lt, flex_batch):
    """Entry 0 (every mode frozen) is the rigid car's χ and entry 2 the 2-mode car's, to 1e-7."""
    assert chi_by_modes.shape == (3,)
    np.testing.assert_allclose(chi_by_modes[0], float(rigid_lt.chi_low_ay), atol=1e-7)
    np.testing.assert_allclose(chi_by_modes[2], float(flex_batch.chi_low_ay[0]), atol=1e-7)
    assert abs(chi_by_modes[1] - chi_by_modes[0]) > 1e-3  # the first (torsion) mode carries the effect


def test_cli_lltd_modes_json(chi_by_modes, rigid):
    result = runner.invoke(app, ["vehicle", "lltd-modes", "--max-modes", "2", "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)
    np.testing.assert_allclose(report["chi_by_modes"], chi_by_modes, atol=1e-12)
    expected = an.chapter3_parameters(rigid)
    assert report["lam"] == pytest.approx(float(expected.lam))
    assert 0.3 < report["chi_eq36"] < 0.7
    bad = runner.invoke(app, ["vehicle", "lltd-modes", "--max-modes", "0"])
    assert bad.exit_code != 0 and "max_modes = 0" in bad.output
