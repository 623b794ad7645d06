"""Roll steer and understeer gradient (section 3.2)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import central_difference
from jax.test_util import check_grads

from jaxveh.analytic import (
    RAD_PER_MS2_TO_DEG_PER_G,
    chassis_twist,
    roll_angles_flexible,
    roll_angles_normalised,
    roll_gradient,
    understeer_gradient,
    understeer_gradient_rigid,
    with_distribution,
)
from jaxveh.analytic._quantities import roll_moments
from jaxveh.params import load_analytic_vehicle

EXACT = 1e-12


@pytest.fixture(scope="module")
def vehicle():
    return load_analytic_vehicle()


def test_rigid_understeer_gradient_is_thesis_value(vehicle):
    # Section 3.2.2: "an understeer gradient, in the linear region, of about 0.74 deg/g".
    assert float(understeer_gradient_rigid(vehicle) * RAD_PER_MS2_TO_DEG_PER_G) == pytest.approx(0.74, abs=0.002)


@pytest.mark.parametrize("lam,mu", [(0.3, 0.3), (0.54, 1.0), (0.8, 5.0)])
def test_roll_angles_forms_agree_and_satisfy_equilibrium(vehicle, lam, mu):
    v = with_distribution(vehicle, lam=lam, mu=mu)
    ay = 7.0
    phi_f, phi_r = roll_angles_flexible(v, ay)
    phi_f2, phi_r2 = roll_angles_normalised(v, ay)
    assert float(phi_f) == pytest.approx(float(phi_f2), rel=EXACT)
    assert float(phi_r) == pytest.approx(float(phi_r2), rel=EXACT)
    # Equilibrium (3.12).
    mF, mR = roll_moments(v)
    assert float(mF * ay - v.kF * phi_f - v.kC * (phi_f - phi_r)) == pytest.approx(0.0, abs=1e-9)
    assert float(mR * ay - v.kR * phi_r + v.kC * (phi_f - phi_r)) == pytest.approx(0.0, abs=1e-9)
    assert float(chassis_twist(v, ay)) == pytest.approx(float(phi_f - phi_r), rel=1e-10)


def test_stiff_chassis_recovers_rigid(vehicle):
    for lam in (0.2, 0.8):
        v = with_distribution(vehicle, lam=lam, mu=1e9)
        phi_f, phi_r = roll_angles_flexible(v, 1.0)
        assert float(phi_f) == pytest.approx(float(roll_gradient(v)), rel=1e-8)
        assert float(phi_r) == pytest.approx(float(roll_gradient(v)), rel=1e-8)
        assert float(understeer_gradient(v)) == pytest.approx(float(understeer_gradient_rigid(v)), rel=1e-8)


def test_rigid_gradient_independent_of_lambda_flexible_is_not(vehicle):
    rigid = [float(understeer_gradient_rigid(with_distribution(vehicle, lam=x))) for x in (0.3, 0.7)]
    assert rigid[0] == pytest.approx(rigid[1], rel=EXACT)
    flex = [float(understeer_gradient(with_distribution(vehicle, lam=x, mu=0.5))) for x in (0.3, 0.7)]
    # Rear-biased roll stiffness loads the rear roll steer: more understeer at high λ (Fig. 3.4a).
    assert flex[1] > flex[0] * 1.05


def test_understeer_gradient_wrt_stiffness_and_lambda(vehicle):
    def ku(x):
        return understeer_gradient(with_distribution(vehicle, lam=x[0], mu=x[1]))

    x0 = np.array([0.35, 0.8])
    g = np.asarray(jax.grad(ku)(jax.numpy.asarray(x0)))
    fd = central_difference(ku, x0, 1e-6)
    np.testing.assert_allclose(g, fd, rtol=1e-6)


def test_check_grads_of_understeer_gradient(vehicle):
    def ku(x):
        return understeer_gradient(with_distribution(vehicle, lam=x[0], mu=x[1]))

    check_grads(ku, (jnp.asarray([0.55, 1.3]),), order=2, modes=("fwd", "rev"), eps=1e-5)
