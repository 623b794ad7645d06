"""Input validation of the tyre API: named errors for meaningless coefficients and
arguments, concrete and traced; lift-off and standstill are the model's business, not errors."""

from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh.tyre as jt
from jaxveh.params import ParameterError

FSAE = jt.load_fsae_tyre()
FIXTURE = jt.read_tir(Path(__file__).parent / "data" / "tyre_mf52_fixture.tir")


@pytest.mark.parametrize(
    "name, value, match",
    [
        ("fnomin", -1.0, r"MagicFormulaTyre\.fnomin must lie in \(0, inf\) \(FNOMIN: Nominal wheel load \[N\]\)"),
        ("sigma_alpha", -0.3, r"MagicFormulaTyre\.sigma_alpha must lie in \(0, inf\) \(SIGMA_ALPHA"),
        ("sigma_kappa", 0.0, r"MagicFormulaTyre\.sigma_kappa must lie in \(0, inf\)"),
        ("vertical_damping", -50.0, r"MagicFormulaTyre\.vertical_damping must lie in \[0, inf\)"),
        ("vertical_stiffness", 0.0, r"MagicFormulaTyre\.vertical_stiffness must lie in \(0, inf\)"),
        ("lmuy", 0.0, r"MagicFormulaTyre\.lmuy must lie in \(0, inf\) \(LMUY: Scale factor of Fy peak friction"),
        ("lky", -1.0, r"MagicFormulaTyre\.lky must lie in \[0, inf\) \(LKY: Scale factor of Fy cornering stiffness"),
        ("pcy1", 0.0, r"MagicFormulaTyre\.pcy1 must lie in \(0, inf\) \(PCY1: Shape factor"),
        ("vxlow", np.nan, r"MagicFormulaTyre\.vxlow must lie in \(0, inf\)"),
    ],
)
def test_bad_coefficients_name_coefficient_and_range(name, value, match):
    with pytest.raises(ParameterError, match=match):
        jt.MagicFormulaTyre(**{name: value})
    bad = eqx.tree_at(lambda t: getattr(t, name), FSAE, jnp.asarray(value))
    with pytest.raises(ParameterError, match=match):
        jt.tyre_forces(bad, 500.0, 0.05, 0.05, 0.0, 11.0)
    with pytest.raises(ParameterError, match=match):
        bad.relaxation_lengths(500.0, 0.0)


def test_mf52_relaxation_coefficients_and_lengths():
    with pytest.raises(ParameterError, match=r"MagicFormulaTyre\.pty2 must lie in \(0, inf\) \(PTY2"):
        jt.MagicFormulaTyre(relaxation_model="mf52", ptx1=2.0, pty1=2.0, pty2=0.0)
    # PKY3 |gamma| > 1 drives the lateral relaxation length negative: refused, not NaN.
    cambered = eqx.tree_at(lambda t: t.pky3, FIXTURE, jnp.asarray(2.0))
    assert float(jt.relaxation_lengths(cambered, 3000.0, 0.1)[1]) > 0.0
    with pytest.raises(ParameterError, match=r"sigma_alpha must lie in \(0, inf\) \(MF 5\.2 lateral relaxation"):
        jt.relaxation_lengths(cambered, 3000.0, 0.6)


def test_tir_file_with_meaningless_value_names_the_file(tmp_path):
    text = jt.format_tir(FSAE).replace("SIGMA_ALPHA              = 0.3", "SIGMA_ALPHA              = -0.3")
    assert "-0.3" in text
    path = tmp_path / "bad.tir"
    path.write_text(text)
    with pytest.raises(jt.TirError, match=r"bad\.tir: MagicFormulaTyre\.sigma_alpha must lie in \(0, inf\)"):
        jt.read_tir(path)


def test_traced_coefficients_checked_at_run_time():
    @eqx.filter_jit
    def fy(pdy1, sigma):
        t = eqx.tree_at(lambda t: (t.pdy1, t.sigma_alpha), FSAE, (pdy1, sigma))
        return jt.tyre_forces(t, 500.0, 0.0, 0.05, 0.0, 11.0).fy + jt.transient_slips(t, jnp.ones(2), 500.0, 0.0)[1]

    assert np.isfinite(float(fy(jnp.asarray(1.5), jnp.asarray(0.3))))
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"MagicFormulaTyre\.pdy1 must lie in \(0, inf\)"):
        fy(jnp.asarray(-1.5), jnp.asarray(0.3))
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"MagicFormulaTyre\.sigma_alpha must lie in \(0, inf\)"):
        fy(jnp.asarray(1.5), jnp.asarray(0.0))
    # vmapped over stacked tyres (built without __init__): one bad tyre stops the batch.
    stacked = jax.tree.map(lambda *x: jnp.stack(x), FSAE, eqx.tree_at(lambda t: t.fnomin, FSAE, jnp.asarray(0.0)))
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"MagicFormulaTyre\.fnomin must lie in \(0, inf\)"):
        eqx.filter_jit(jax.vmap(lambda t: jt.tyre_forces(t, 500.0, 0.0, 0.05, 0.0, 11.0).fy))(stacked)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: jt.inclination_angle(0.01, 0.0), r"side must be \+1 \(left wheel\) or -1 \(right wheel\)"),
        (lambda: jt.low_speed_denominator(1.0, 0.0), r"vxlow must lie in \(0, inf\)"),
        (lambda: jt.pure_slip_curves(FSAE, n=1), r"n must be a Python int >= 2"),
        (lambda: jt.pure_slip_curves(FSAE, kappa_max=0.0), r"kappa_max must lie in \(0, inf\)"),
        (lambda: jt.pure_slip_curves(FSAE, alpha_max_deg=90.0), r"alpha_max_deg must lie in \(0, 90\)"),
        (lambda: jt.pure_slip_curves(FSAE, loads=[500.0, np.nan]), r"loads must lie in \(-inf, inf\)"),
        (lambda: jt.combined_slip_curves(FSAE, n=0), r"n must be a Python int >= 2"),
        (lambda: jt.fit_tir(_measurements(), FSAE, rtol=0.0), r"rtol must lie in \(0, inf\)"),
        (lambda: jt.fit_tir(_measurements(), FSAE, max_steps=0), r"max_steps must be a Python int >= 1"),
        (lambda: jt.fit_tir(_measurements(), eqx.tree_at(lambda t: t.lfzo, FSAE, jnp.asarray(0.0))),
         r"MagicFormulaTyre\.lfzo must lie in \(0, inf\)"),
    ],
)
def test_bad_arguments_name_argument_and_range(call, match):
    with pytest.raises(ParameterError, match=match):
        call()


def _measurements():
    z = jnp.zeros(3)
    return jt.TyreMeasurements(jnp.full(3, 500.0), z, z, z, z, z, z, jnp.full(3, 11.0))


def test_traced_side_is_checked():
    gamma = eqx.filter_jit(lambda side: jt.inclination_angle(0.02, side))
    assert float(gamma(jnp.asarray(-1.0))) == pytest.approx(0.02)
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"side must be \+1"):
        gamma(jnp.asarray(0.5))


def test_lift_off_and_standstill_are_not_refused():
    """Fz <= 0 (lift-off) and zero speed are handled by the model, finite and smooth."""
    f = jt.tyre_forces(FSAE, -200.0, 0.1, 0.1, 0.0, 0.0)
    assert all(float(x) == 0.0 for x in f)
    kappa, alpha = jt.steady_slips(FSAE, 0.0, 0.3, -0.2)
    assert np.isfinite(float(kappa)) and np.isfinite(float(alpha))
    rhs = jt.transient_slip_rhs(FSAE, jnp.asarray([0.01, -0.01]), 0.0, 0.0, 0.0, 0.2, 0.1)
    assert np.all(np.isfinite(np.asarray(rhs)))
    assert float(jt.vertical_force(FSAE, -0.01, 0.0)) == 0.0
    curves = jt.pure_slip_curves(FSAE, loads=[0.0, 500.0], n=11)
    assert float(jnp.max(jnp.abs(curves.fy[0]))) == 0.0
