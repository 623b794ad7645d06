"""MF 5.2 forces: signs, symmetry, Fig. B.1 peaks, closed forms, combined slip, robustness,
gradients (slips and coefficients) against finite differences, vmap, no retrace."""

import dataclasses
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import central_difference
from jax.test_util import check_grads

import jaxveh.tyre as jt
from jaxveh.params import as_float

FSAE = jt.load_fsae_tyre()
FIXTURE = jt.read_tir(Path(__file__).parent / "data" / "tyre_mf52_fixture.tir")
FORCES = jax.jit(jt.tyre_forces)
#: slips/loads on a grid: vmap over points, tyre shared
GRID = jax.jit(jax.vmap(jt.tyre_forces, in_axes=(None, 0, 0, 0, 0, 0)))

#: Peak values read from Fig. B.1 (axes only: the thesis gives no table). |Fy| and Fx at
#: 1000 N "about 1500 N" and "1300-1500 N" (issue #3, DESIGN.md), Mz peak 20-35 Nm.
FIG_B1_FY_1000 = (1350.0, 1550.0)
FIG_B1_FX_1000 = (1300.0, 1500.0)
FIG_B1_MZ_1000 = (20.0, 35.0)
#: peaks inside the plotted slip ranges, away from the edges (falling curves after the peak)
KAPPA_PEAK_RANGE = (0.05, 0.25)
ALPHA_PEAK_RANGE_DEG = (4.0, 12.0)
#: round-off level for exact symmetries (N)
EXACT = 1e-9
#: finite-difference gradient tolerance (central differences, h = 1e-6 relative)
FD_RTOL = 1e-5


def _pt(fz, kappa, alpha, gamma=0.0, vx=11.0):
    return [jnp.asarray(x, dtype=jnp.float64) for x in (fz, kappa, alpha, gamma, vx)]


def test_iso_w_signs():
    f = FORCES(FSAE, *_pt(750.0, 0.05, 0.0))
    assert float(f.fx) > 0.0  # driving slip -> traction
    f = FORCES(FSAE, *_pt(750.0, -0.05, 0.0))
    assert float(f.fx) < 0.0  # braking
    f = FORCES(FSAE, *_pt(750.0, 0.0, np.deg2rad(3.0)))
    assert float(f.fy) < 0.0 and float(f.mz) > 0.0  # ISO-W: alpha > 0 gives Fy < 0, aligning Mz > 0
    f = FORCES(FSAE, *_pt(750.0, 0.0, 0.0, gamma=0.05))
    assert float(f.fy) < 0.0  # camber thrust towards the lean (-y for gamma > 0)
    assert float(FORCES(FSAE, *_pt(750.0, 0.0, 0.0, vx=11.0)).my) < 0.0  # rolling resistance
    assert float(FORCES(FSAE, *_pt(750.0, 0.0, 0.0, vx=-11.0)).my) > 0.0


def test_symmetry_of_a_symmetric_tyre():
    """FSAE Fx and Fy have no shifts: Fx(-k) = -Fx(k), Fy(-a) = -Fy(a), Fy(k, a) = Fy(-k, a)."""
    k = jnp.linspace(-0.3, 0.3, 61)
    a = jnp.deg2rad(jnp.linspace(-15.0, 15.0, 61))
    n = k.shape[0]
    fz, z, vx = jnp.full(n, 600.0), jnp.zeros(n), jnp.full(n, 11.0)
    fx = GRID(FSAE, fz, k, z, z, vx).fx
    np.testing.assert_allclose(fx, -fx[::-1], atol=EXACT)
    fy = GRID(FSAE, fz, z, a, z, vx).fy
    np.testing.assert_allclose(fy, -fy[::-1], atol=EXACT)
    aa = jnp.full(n, np.deg2rad(5.0))
    fyk = GRID(FSAE, fz, k, aa, z, vx).fy
    np.testing.assert_allclose(fyk, fyk[::-1], atol=EXACT)


def test_closed_forms_at_zero_slip():
    """Slip stiffnesses and peaks equal their MF 5.2 closed forms (no shifts in FSAE)."""
    t, fz = FSAE, 900.0
    fz0 = float(t.fnomin)
    dfz = (fz - fz0) / fz0
    kx = jax.grad(lambda k: FORCES(t, *_pt(fz, k, 0.0)).fx)(0.0)
    np.testing.assert_allclose(kx, fz * float(t.pkx1) * np.exp(float(t.pkx3) * dfz), rtol=1e-10)
    ky = jax.grad(lambda a: FORCES(t, *_pt(fz, 0.0, a)).fy)(0.0)
    ky_ref = float(t.pky1) * fz0 * np.sin(2 * np.arctan(fz / (float(t.pky2) * fz0)))
    np.testing.assert_allclose(ky, ky_ref, rtol=1e-10)
    rows = jt.peak_table(t, loads=(fz,), n=20001)[0]
    # peak of D sin(C atan(.)) is D = mu Fz when C > 1 and the peak lies in the range
    np.testing.assert_allclose(rows["fx_peak"], (float(t.pdx1) + float(t.pdx2) * dfz) * fz, rtol=1e-6)
    np.testing.assert_allclose(rows["fy_peak"], (float(t.pdy1) + float(t.pdy2) * dfz) * fz, rtol=1e-6)


def _np_fy0(t, fz, alpha, gamma):
    """Independent NumPy transcription of MF 5.2 pure lateral force (Pacejka 2006, 4.E19-30)."""
    g = {k: float(v) for k, v in t.__dict__.items() if not isinstance(v, (str, tuple, int))}
    fz0 = g["fnomin"] * g["lfzo"]
    dfz = (fz - fz0) / fz0
    gy = gamma * g["lgay"]
    shy = (g["phy1"] + g["phy2"] * dfz) * g["lhy"] + g["phy3"] * gy
    ay = alpha + shy
    c = g["pcy1"] * g["lcy"]
    d = (g["pdy1"] + g["pdy2"] * dfz) * (1 - g["pdy3"] * gy**2) * g["lmuy"] * fz
    e = min((g["pey1"] + g["pey2"] * dfz) * (1 - (g["pey3"] + g["pey4"] * gy) * np.sign(ay)) * g["ley"], 1.0)
    k = g["pky1"] * g["fnomin"] * np.sin(2 * np.arctan(fz / (g["pky2"] * fz0)))
    k = k * (1 - g["pky3"] * abs(gy)) * g["lfzo"] * g["lky"]
    b = k / (c * d)
    sv = fz * ((g["pvy1"] + g["pvy2"] * dfz) * g["lvy"] + (g["pvy3"] + g["pvy4"] * dfz) * gy) * g["lmuy"]
    return d * np.sin(c * np.arctan(b * ay - e * (b * ay - np.arctan(b * ay)))) + sv


def test_pure_lateral_matches_independent_numpy():
    for fz, a, g in [(3500.0, 0.05, 0.0), (2000.0, -0.12, 0.03), (5000.0, 0.3, -0.05)]:
        fy = float(FORCES(FIXTURE, *_pt(fz, 0.0, a, g, 20.0)).fy)
        np.testing.assert_allclose(fy, _np_fy0(FIXTURE, fz, a, g), rtol=1e-12)


def test_fig_b1_peaks():
    rows = {r["fz"]: r for r in jt.peak_table(FSAE)}
    r = rows[1000.0]
    assert FIG_B1_FY_1000[0] <= r["fy_peak"] <= FIG_B1_FY_1000[1]
    assert FIG_B1_FX_1000[0] <= r["fx_peak"] <= FIG_B1_FX_1000[1]
    assert FIG_B1_MZ_1000[0] <= r["mz_max"] <= FIG_B1_MZ_1000[1]
    # Fig. B.1(c) axis runs from -20 to 40 Nm: the curves stay inside it
    assert all(-20.0 <= rr["mz_min"] and rr["mz_max"] <= 40.0 for rr in rows.values())
    for rr in rows.values():
        assert KAPPA_PEAK_RANGE[0] <= rr["kappa_peak"] <= KAPPA_PEAK_RANGE[1]
        assert ALPHA_PEAK_RANGE_DEG[0] <= rr["alpha_peak_deg"] <= ALPHA_PEAK_RANGE_DEG[1]
    # peaks grow with load, friction coefficient falls with load (load sensitivity)
    loads = sorted(rows)
    assert all(rows[a]["fy_peak"] < rows[b]["fy_peak"] for a, b in zip(loads, loads[1:]))
    assert all(rows[a]["fy_peak"] / a > rows[b]["fy_peak"] / b for a, b in zip(loads, loads[1:]))


#: the normalised combined force may exceed the friction ellipse by this much (MF G-functions
#: are not an exact ellipse)
ELLIPSE_SLACK = 0.02


def test_combined_slip_stays_within_friction_envelope():
    for fz in (250.0, 750.0, 1000.0):
        rows = jt.peak_table(FSAE, loads=(fz,))[0]
        alphas, kappa, fx, fy = jt.combined_slip_curves(FSAE, fz=fz, alphas_deg=(1.0, 3.0, 6.0, 10.0, 15.0))
        pure = jt.pure_slip_curves(FSAE, loads=(fz,), n=kappa.shape[0])
        ell = np.sqrt((np.asarray(fx) / rows["fx_peak"]) ** 2 + (np.asarray(fy) / rows["fy_peak"]) ** 2)
        assert ell.max() <= 1.0 + ELLIPSE_SLACK
        # adding slip angle reduces |Fx| at every kappa; adding kappa reduces |Fy|
        assert np.all(np.abs(np.asarray(fx)) <= np.abs(np.asarray(pure.fx[0]))[None, :] + EXACT)
        fy_pure = np.abs(np.asarray(FORCES(FSAE, *_pt(fz, 0.0, alphas[:, None])).fy))
        assert np.all(np.abs(np.asarray(fy)) <= fy_pure + EXACT)


EXTREME = [1e-300, 1e-12, 0.0, -1e-12, -5.0, 1e6, 1e300, -1e300]


def test_no_nan_for_extreme_finite_inputs():
    vals = jnp.asarray(EXTREME)
    mesh = jnp.meshgrid(vals, vals, vals, jnp.asarray([-1.0, 0.0, 0.5, 1e300]), vals, indexing="ij")
    grid = jnp.stack(mesh, -1).reshape(-1, 5)
    for tyre in (FSAE, FIXTURE):
        f = GRID(tyre, grid[:, 0], grid[:, 1], grid[:, 2], grid[:, 3], grid[:, 4])
        for v in f:
            assert np.all(np.isfinite(np.asarray(v)))


def test_lift_off_is_zero_and_continuous():
    for fz in (0.0, -1.0, -1e6):
        f = FORCES(FSAE, *_pt(fz, 0.1, 0.1, 0.02))
        assert all(float(v) == 0.0 for v in f)
    fzs = jnp.linspace(-5.0, 30.0, 3501)
    n = fzs.shape[0]
    f = GRID(FSAE, fzs, jnp.full(n, 0.1), jnp.full(n, 0.1), jnp.zeros(n), jnp.full(n, 11.0))
    for v in f:
        jumps = np.abs(np.diff(np.asarray(v)))
        assert jumps.max() < 1.0  # no jump: at most 1 N (Nm) per 0.01 N of load here


@pytest.mark.parametrize("wrt", ["fz", "kappa", "alpha", "vx"])
@pytest.mark.parametrize("at", [0.0, 1e-9, -1e-9])
def test_gradients_finite_through_singular_points(wrt, at):
    base = dict(fz=600.0, kappa=0.05, alpha=0.05, gamma=0.0, vx=11.0)
    base[wrt] = at
    names = list(base)

    def out(x):
        args = dict(base, **{wrt: x})
        f = jt.tyre_forces(FSAE, *[jnp.asarray(args[k]) for k in names])
        return f.fx + f.fy + f.mz + f.mx + f.my

    g = jax.grad(out)(jnp.asarray(at))
    assert np.isfinite(float(g))
    # and the combined-slip Mz at kappa = alpha = 0 (equivalent-slip square root)
    gz = jax.grad(lambda s: jt.tyre_forces(FSAE, 600.0, s, s, 0.0, 11.0).mz)(jnp.asarray(at))
    assert np.isfinite(float(gz))


def test_continuity_through_zero_slip_and_speed():
    s = jnp.linspace(-1e-6, 1e-6, 201)
    n = s.shape[0]
    fz, z = jnp.full(n, 700.0), jnp.zeros(n)
    v11 = jnp.full(n, 11.0)
    for f in (GRID(FSAE, fz, s, s, z, v11), GRID(FIXTURE, fz * 5, s, s, z, v11), GRID(FIXTURE, fz * 5, z, z, z, s)):
        for v in f:
            assert np.abs(np.diff(np.asarray(v))).max() < 1e-2


def test_gradient_wrt_slips_matches_finite_differences():
    x0 = np.array([700.0, 0.07, 0.06, 0.02])

    def scalar(x):
        f = jt.tyre_forces(FIXTURE, x[0] * 5.0, x[1], x[2], x[3], 20.0)
        return f.fx + 2.0 * f.fy + 30.0 * f.mz + 10.0 * f.mx

    g = jax.grad(scalar)(jnp.asarray(x0))
    fd = central_difference(scalar, x0, 1e-6)
    np.testing.assert_allclose(g, fd, rtol=FD_RTOL, atol=1e-6)


def test_check_grads_wrt_operating_point():
    """All five outputs in load (kN), slips and camber, forward and reverse mode."""

    def outputs(x):
        return jnp.stack(jt.tyre_forces(FIXTURE, 1e3 * x[0], x[1], x[2], x[3], 20.0))

    check_grads(outputs, (jnp.asarray([3.5, 0.06, 0.07, 0.03]),), order=1, modes=("fwd", "rev"), eps=1e-6, rtol=1e-5)


def test_gradient_wrt_every_coefficient_matches_finite_differences():
    """d(Fx + Fy + Mz)/d(coefficient) for all coefficients of the fixture at one point."""
    params, static = eqx.partition(FIXTURE, eqx.is_inexact_array)

    def scalar(p):
        f = jt.tyre_forces(eqx.combine(p, static), 3000.0, 0.06, 0.07, 0.03, 20.0)
        return f.fx + f.fy + 30.0 * f.mz + 10.0 * (f.mx + f.my)

    grads = jax.jit(jax.grad(scalar))(params)
    names = jt.coefficient_names()
    flat = np.array([float(getattr(params, n)) for n in names])

    def from_flat(v):
        return scalar(eqx.tree_at(lambda p: [getattr(p, n) for n in names], params, [v[i] for i in range(len(names))]))

    h = 1e-6 * np.maximum(np.abs(flat), 1.0)
    f_jit = jax.jit(jax.vmap(from_flat))
    steps = np.diag(h)
    fd = (np.asarray(f_jit(jnp.asarray(flat + steps))) - np.asarray(f_jit(jnp.asarray(flat - steps)))) / (2 * h)
    g = np.array([float(getattr(grads, n)) for n in names])
    np.testing.assert_allclose(g, fd, rtol=1e-5, atol=1e-4)
    assert np.count_nonzero(g) > 100  # most coefficients influence this point


def test_vmap_over_loads_and_over_tyres(tmp_path):
    loads = jnp.asarray([250.0, 500.0, 750.0, 1000.0])
    per_load = jax.vmap(lambda fz: jt.tyre_forces(FSAE, fz, 0.1, 0.05, 0.0, 11.0))(loads)
    for i, fz in enumerate(np.asarray(loads)):
        np.testing.assert_allclose(per_load.fy[i], FORCES(FSAE, *_pt(fz, 0.1, 0.05)).fy, rtol=1e-13)
    other = eqx.tree_at(lambda t: t.pdy1, FSAE, FSAE.pdy1 * 1.1)
    stacked = jax.tree.map(lambda *x: jnp.stack(x), FSAE, other)
    per_tyre = jax.vmap(lambda t: jt.tyre_forces(t, 600.0, 0.0, 0.15, 0.0, 11.0))(stacked)
    for i, t in enumerate((FSAE, other)):
        np.testing.assert_allclose(per_tyre.fy[i], FORCES(t, *_pt(600.0, 0.0, 0.15)).fy, rtol=1e-13)
    assert float(per_tyre.fy[1]) < float(per_tyre.fy[0]) < 0.0  # more grip, more (negative) force
    # tyres from different files (different static extras) stack with stack_tyres
    written = jt.write_tir(tmp_path / "f.tir", dataclasses.replace(FIXTURE, extras=()))
    both = jt.stack_tyres([FIXTURE, jt.read_tir(written)])
    fy = jax.vmap(lambda t: jt.tyre_forces(t, 3000.0, 0.02, 0.05, 0.01, 20.0).fy)(both)
    np.testing.assert_allclose(fy[0], fy[1], rtol=1e-14)
    with pytest.raises(ValueError, match="differ in"):
        jt.stack_tyres([FSAE, FIXTURE])


def test_no_retrace_when_values_change():
    @eqx.filter_jit
    @eqx.debug.assert_max_traces(max_traces=1)
    def run(tyre, fz):
        return jt.tyre_forces(tyre, fz, 0.05, 0.05, 0.0, 11.0).fy

    run(FSAE, jnp.asarray(500.0))
    run(eqx.tree_at(lambda t: t.pky1, FSAE, as_float(-35.0)), jnp.asarray(800.0))  # as_float: not weak-typed


def test_scalar_outputs_and_dtypes():
    f = FORCES(FSAE, *_pt(500.0, 0.1, 0.1))
    assert all(v.shape == () and v.dtype == jnp.float64 for v in f)


def test_lift_off_transition_is_smooth_at_zero_load():
    """Zero slope at fz = 0 (C1 lift-off) and exact MF above 1 % of FNOMIN."""
    dfy = jax.grad(lambda fz: jt.tyre_forces(FSAE, fz, 0.05, 0.1, 0.0, 11.0).fy)
    assert float(dfy(jnp.asarray(1e-9))) == pytest.approx(0.0, abs=1e-6)
    assert float(dfy(jnp.asarray(-1.0))) == 0.0
    floor = 0.01 * float(FSAE.fnomin)
    up = float(dfy(jnp.asarray(floor + 1e-9)))
    down = float(dfy(jnp.asarray(floor - 1e-9)))
    assert down == pytest.approx(up, rel=0.1)  # secant vs tangent of a nearly linear curve


def test_mirror_symmetric_tyre_is_exactly_symmetric():
    """Every coefficient perturbed at random (the file's tyre has few asymmetric ones), then
    :func:`mirror_symmetric`: Fy, Mz, Mx odd and Fx, My even under (alpha, gamma) ->
    (-alpha, -gamma) to round-off, which the perturbed tyre itself is far from. Fails if the
    list of asymmetric coefficients misses one."""
    from jaxveh.tyre import coefficient_names, load_fsae_tyre, mirror_symmetric, tyre_forces

    rng = np.random.default_rng(1)
    tyre = load_fsae_tyre()
    names = [n for n in coefficient_names() if n[0] in "pqrs" and n[1:3].isalpha() and n[-1].isdigit()]
    assert len(names) > 80
    tyre = eqx.tree_at(lambda t: tuple(getattr(t, n) for n in names), tyre,
                       tuple(getattr(tyre, n) + 0.02 * rng.uniform(-1.0, 1.0) for n in names))
    fz, kappa = rng.uniform(200.0, 2000.0, 200), rng.uniform(-0.3, 0.3, 200)
    alpha, gamma = rng.uniform(-0.3, 0.3, 200), rng.uniform(-0.08, 0.08, 200)
    parity = {"fx": 1.0, "fy": -1.0, "mx": -1.0, "my": 1.0, "mz": -1.0}
    for t, symmetric in ((tyre, False), (mirror_symmetric(tyre), True)):
        left = jax.vmap(lambda *x, t=t: tyre_forces(t, *x))(fz, kappa, alpha, gamma)
        right = jax.vmap(lambda *x, t=t: tyre_forces(t, *x))(fz, kappa, -alpha, -gamma)
        gaps = {k: float(np.max(np.abs(getattr(left, k) - s * getattr(right, k))) / np.max(np.abs(getattr(left, k))))
                for k, s in parity.items()}
        if symmetric:
            assert max(gaps.values()) < 1e-12, gaps
        else:
            assert min(gaps.values()) > 1e-3, gaps
