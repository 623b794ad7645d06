"""Lateral load transfer (section 3.1): closed forms, (3.5) vs (3.6), gradients."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import central_difference
from jax.test_util import check_grads

from jaxveh.analytic import (
    chi,
    chi_from_transfer,
    chi_rigid,
    chi_sensitivity,
    load_transfer_flexible,
    load_transfer_rigid,
    with_distribution,
    zeta,
)
from jaxveh.analytic._quantities import roll_moments, sprung_split
from jaxveh.params import load_analytic_vehicle

#: Closed forms evaluated in float64: agreement to round-off.
EXACT = 1e-12


@pytest.fixture(scope="module")
def vehicle():
    return load_analytic_vehicle()


def test_thesis_values(vehicle):
    # Section 3.3.2: λ = 0.54, µ = 1, ζ = 0.46 for the Appendix A car.
    assert float(zeta(vehicle)) == pytest.approx(0.466, abs=0.005)
    v = with_distribution(vehicle, lam=0.54, mu=1.0)
    assert float(v.kC) == pytest.approx(float(vehicle.kF + vehicle.kR))


def test_eq_3_3_equals_eq_3_4(vehicle):
    # χ0 = λ ds ms/(hG m) + zF msF/(hG m) + huF muF/(hG m) with ds = hs - zs at the sprung c.g.
    msF, msR = sprung_split(vehicle)
    ms, l_s = vehicle.ms, vehicle.as_ + vehicle.bs
    hs = (msF * vehicle.hsF + msR * vehicle.hsR) / ms
    zs = vehicle.zF + (vehicle.zR - vehicle.zF) * vehicle.as_ / l_s
    for lam in (0.2, 0.54, 0.9):
        v = with_distribution(vehicle, lam=lam)
        mh = v.m * v.hG
        expected = lam * (hs - zs) * ms / mh + v.zF * msF / mh + v.huF * v.muF / mh
        assert float(chi_rigid(v)) == pytest.approx(float(expected), rel=EXACT)


@pytest.mark.parametrize("lam,mu", [(0.3, 0.2), (0.54, 1.0), (0.8, 7.0), (0.05, 0.1)])
def test_eq_3_5_equals_eq_3_6(vehicle, lam, mu):
    v = with_distribution(vehicle, lam=lam, mu=mu)
    assert float(chi_from_transfer(v)) == pytest.approx(float(chi(v)), rel=EXACT)


@pytest.mark.parametrize("lam", [0.0, 1.0])
def test_limit_distributions_do_not_depend_on_mu(vehicle, lam):
    msF, _ = sprung_split(vehicle)
    mF, mR = roll_moments(vehicle)
    mh = vehicle.m * vehicle.hG
    unsprung_and_axle = (vehicle.zF * msF + vehicle.huF * vehicle.muF) / mh
    expected = unsprung_and_axle + (lam * (mF + mR)) / mh
    for mu in (0.1, 1.0, 10.0):
        assert float(chi(with_distribution(vehicle, lam=lam, mu=mu))) == pytest.approx(float(expected), rel=EXACT)


def test_lambda_equal_zeta_makes_mu_irrelevant(vehicle):
    lam = zeta(vehicle)
    values = [float(chi(with_distribution(vehicle, lam=lam, mu=mu))) for mu in (0.05, 0.5, 5.0)]
    np.testing.assert_allclose(values, float(chi_rigid(with_distribution(vehicle, lam=lam))), rtol=EXACT)


def test_infinite_stiffness_gives_rigid(vehicle):
    for lam in (0.3, 0.7):
        v = with_distribution(vehicle, lam=lam, mu=1e9)
        assert float(chi(v)) == pytest.approx(float(chi_rigid(v)), rel=1e-8)
        assert float(chi_sensitivity(v)) == pytest.approx(float(chi_sensitivity(v, rigid=True)), rel=1e-7)


def test_chassis_stiffness_redistributes_but_keeps_total(vehicle):
    ay = 9.0
    for mu in (0.1, 1.0):
        v = with_distribution(vehicle, lam=0.3, mu=mu)
        f_flex, r_flex = load_transfer_flexible(v, ay)
        f_rig, r_rig = load_transfer_rigid(v, ay)
        assert float(f_flex + r_flex) == pytest.approx(float(f_rig + r_rig), rel=EXACT)
        assert float(f_flex) != pytest.approx(float(f_rig), rel=1e-3)


def test_sensitivity_gradient_against_finite_differences(vehicle):
    v = with_distribution(vehicle, mu=1.0)
    for lam in (0.3, 0.54, 0.7):
        g = chi_sensitivity(with_distribution(v, lam=lam))
        fd = central_difference(lambda x: chi(with_distribution(v, lam=x[0])), np.array([lam]), 1e-6)[0]
        assert float(g) == pytest.approx(fd, rel=1e-7)
    # Gradient with respect to the chassis stiffness kC (Nm/rad).
    g_kc = jax.grad(lambda kc: chi(with_distribution(v, lam=0.3, mu=kc / (v.kF + v.kR))))(v.kC)
    def chi_of_kc(x):
        return chi(with_distribution(v, lam=0.3, mu=x[0] / (v.kF + v.kR)))

    fd_kc = central_difference(chi_of_kc, np.array([float(v.kC)]), 1.0)[0]
    assert float(g_kc) == pytest.approx(fd_kc, rel=1e-6)


def test_vmap_over_distribution(vehicle):
    lams = jnp.linspace(0.1, 0.9, 5)
    batched = jax.vmap(lambda lam: chi(with_distribution(vehicle, lam=lam, mu=2.0)))(lams)
    single = [float(chi(with_distribution(vehicle, lam=float(x), mu=2.0))) for x in lams]
    np.testing.assert_allclose(batched, single, rtol=EXACT)


def test_new_parameter_values_do_not_retrace(vehicle):
    import equinox as eqx

    @eqx.filter_jit
    @eqx.debug.assert_max_traces(max_traces=1)
    def summary(v):
        return chi(v), chi_sensitivity(v)

    summary(vehicle)
    summary(with_distribution(vehicle, lam=0.3, mu=2.0))
    summary(with_distribution(vehicle, lam=0.7))


def test_check_grads_of_chi_in_lambda_and_mu(vehicle):
    """Forward and reverse mode, first and second order, against JAX's finite differences."""

    def chi_of(x):
        return chi(with_distribution(vehicle, lam=x[0], mu=x[1]))

    check_grads(chi_of, (jnp.asarray([0.45, 0.8]),), order=2, modes=("fwd", "rev"), eps=1e-5)
    # and of the sensitivity χλ (itself a jax.grad) in µ: a third derivative of χ overall.
    check_grads(lambda m: chi_sensitivity(with_distribution(vehicle, mu=m)), (jnp.asarray(2.0),), order=1,
                modes=("fwd", "rev"), eps=1e-5)
