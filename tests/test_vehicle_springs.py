"""Spring-damper laws (eq. 6.10): linear law, tables with linear continuation, the bump
stop, gradients, and named errors."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh import vehicle
from jaxveh._core import ParameterError


def test_linear_law_is_the_linear_formula():
    law = vehicle.linear_spring_damper(30_000.0, 0.28, 1500.0)
    for length, rate in ((0.26, -0.3), (0.28, 0.0), (0.3, 0.4), (0.1, 2.5)):
        np.testing.assert_allclose(law(length, rate), 30_000.0 * (0.28 - length) - 1500.0 * rate, rtol=1e-13, atol=1e-9)


def test_tables_interpolate_and_continue_with_their_end_slopes():
    law = vehicle.SpringDamperLaw(
        spring_length=jnp.asarray([0.24, 0.26, 0.28]), spring_force=jnp.asarray([1500.0, 600.0, 0.0]),
        damper_rate=jnp.asarray([-0.5, 0.0, 0.5]), damper_force=jnp.asarray([1000.0, 0.0, -600.0]))
    np.testing.assert_allclose(law.spring(jnp.asarray([0.24, 0.25, 0.26, 0.27, 0.28])),
                               [1500.0, 1050.0, 600.0, 300.0, 0.0], rtol=1e-13, atol=1e-9)
    np.testing.assert_allclose(law.spring(0.22), 1500.0 + 0.02 * 45_000.0, rtol=1e-13)  # below the table
    np.testing.assert_allclose(law.spring(0.3), -0.02 * 30_000.0, rtol=1e-13)  # beyond it
    np.testing.assert_allclose(law.damper(-1.0), 2000.0, rtol=1e-13)  # bump slope 2000 N/(m/s)
    np.testing.assert_allclose(law.damper(0.25), -300.0, rtol=1e-13)
    np.testing.assert_allclose(jax.grad(law.spring)(0.27), -30_000.0, rtol=1e-12)


def test_bump_stop():
    law = vehicle.linear_spring_damper(20_000.0, 0.28, 0.0, bump_stop_length=0.25, bump_stop_rate=3e5)
    free = vehicle.linear_spring_damper(20_000.0, 0.28, 0.0)
    assert abs(float(law(0.262, 0.0) - free(0.262, 0.0))) < 1e-2  # 12 mm off the stop: < 0.01 N
    np.testing.assert_allclose(law(0.24, 0.0) - free(0.24, 0.0), 3e5 * 0.01, rtol=1e-3)  # 10 mm in
    stiffness = -jax.grad(lambda x: law(x, 0.0))(0.24)
    np.testing.assert_allclose(stiffness, 20_000.0 + 3e5, rtol=1e-3)


def test_named_errors():
    with pytest.raises(ParameterError, match="spring table.*increasing"):
        vehicle.SpringDamperLaw(spring_length=jnp.asarray([0.3, 0.2]), spring_force=jnp.asarray([0.0, 1.0]),
                                damper_rate=jnp.asarray([-1.0, 1.0]), damper_force=jnp.asarray([1.0, -1.0]))
    with pytest.raises(ParameterError, match="damper table.*equal length"):
        vehicle.SpringDamperLaw(spring_length=jnp.asarray([0.2, 0.3]), spring_force=jnp.asarray([1.0, 0.0]),
                                damper_rate=jnp.asarray([-1.0, 0.0, 1.0]), damper_force=jnp.asarray([1.0, -1.0]))
    with pytest.raises(ParameterError, match="bump_stop_rate"):
        vehicle.linear_spring_damper(20_000.0, 0.28, 0.0, bump_stop_rate=-1.0)
    with pytest.raises(ParameterError, match="rate"):
        vehicle.linear_spring_damper(-5.0, 0.28, 0.0)
    with pytest.raises(ParameterError, match="damping"):
        vehicle.linear_spring_damper(5.0, 0.28, -1.0)
