"""Parameter validation of the multibody library: every number an optimiser may change is
checked at the entry points (simulate, assemble, linearise), by name, for concrete and for
traced values."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh import ParameterError, multibody as mb, vehicle
from jaxveh.multibody import _examples as ex


@pytest.fixture(scope="module")
def pendulum():
    system, params = ex.double_pendulum()
    q, z = ex.double_pendulum_state(system, params, (0.3, -0.5), (1.0, 2.0))
    return system, params, q, z


@pytest.mark.parametrize(
    "where, value, message",
    [
        (lambda p: p.bodies[0].mass, -1.0, r"body 'B1' mass \(kg\) must lie in \[0, inf\); got -1"),
        (lambda p: p.bodies[1].inertia, -np.eye(3), r"body 'B2' inertia \(smallest eigenvalue / largest\)"),
        (lambda p: p.gravity, jnp.asarray([0.0, jnp.nan, 0.0]), r"gravity \(m/s\^2\) must lie in"),
        (lambda p: p.points[1].position, jnp.asarray([0.0, 0.0, jnp.inf]), r"point 'P1' position \(m\)"),
    ],
)
def test_bad_body_values_are_named(pendulum, where, value, message):
    system, params, q, z = pendulum
    bad = eqx.tree_at(where, params, jnp.asarray(value, jnp.float64))
    with pytest.raises(ParameterError, match=message):
        mb.checked_params(system, bad)
    with pytest.raises(ParameterError, match=message):
        mb.simulate(system, bad, q, z, 0.0, 0.1)


def test_link_length_and_coupling_are_checked():
    system, params = vehicle.quarter_car()
    k = system.joint_names.index("track_rod")
    bad = eqx.tree_at(lambda p: p.joints[k].length, params, jnp.asarray(0.0))
    with pytest.raises(ParameterError, match=r"link 'track_rod' length \(m\) must lie in \(0, inf\)"):
        mb.assemble(system, bad, vehicle.quarter_car_design_q(system), inputs=lambda t: jnp.zeros((1,)))
    fsystem, fparams = ex.flexible_pendulum()
    bad = eqx.tree_at(lambda p: p.bodies[0].coupling, fparams, jnp.asarray(1.5))
    with pytest.raises(ParameterError, match=r"body 'beam' coupling must lie in \[0, 1\]; got 1.5"):
        mb.checked_params(fsystem, bad)


def test_traced_bad_value_fails_at_run_time(pendulum):
    """Inside jit (an optimiser's traced mass) the same check raises instead of a NaN."""
    system, params, q, z = pendulum

    @jax.jit
    def final_angle(m1):
        p = eqx.tree_at(lambda pp: pp.bodies[0].mass, params, m1)
        return mb.simulate(system, p, q, z, 0.0, 0.05, rtol=1e-6, atol=1e-8).q[-1, 0]

    assert np.isfinite(float(final_angle(jnp.asarray(2.0))))
    with pytest.raises(Exception, match=r"body 'B1' mass \(kg\) must lie in \[0, inf\)"):
        final_angle(jnp.asarray(-2.0)).block_until_ready()


def test_check_range_under_grad_and_jit_names_the_field():
    """Concrete flags with traced values (un-jitted grad) and concrete values inside jit."""
    from jaxveh._core import check_range

    with pytest.raises(ParameterError, match=r"^mass \(kg\) must lie in \[0, inf\)\n"):
        jax.grad(lambda m: check_range("mass (kg)", m, low=0.0))(-1.0)
    with pytest.raises(Exception, match=r"mass \(kg\) must lie in \[0, inf\)"):
        jax.jit(lambda x: x + check_range("mass (kg)", jnp.asarray(-1.0), low=0.0))(1.0).block_until_ready()
    assert float(jax.grad(lambda m: check_range("mass (kg)", m, low=0.0) ** 2)(3.0)) == 6.0
