"""ZOH discretisation against SciPy (``cont2discrete``, ``expm``)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg
import scipy.signal
from helpers import assert_grad_matches_fd
from jax.test_util import check_grads

from jaxveh.control import zoh

#: expm via Pade in both libraries; agreement to a few ulps of the entries' scale.
EXPM_RTOL = 1e-12
EXPM_ATOL = 1e-13
DT = 0.01


def _random_system(seed, n=5, m=2):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, n)) * 3.0, rng.normal(size=(n, m))


@pytest.mark.parametrize("seed", [0, 1])
def test_zoh_matches_scipy_cont2discrete(seed):
    a_c, b_c = _random_system(seed)
    a_d, b_d = zoh(jnp.asarray(a_c), jnp.asarray(b_c), DT)
    ref = scipy.signal.cont2discrete((a_c, b_c, np.eye(5), np.zeros((5, 2))), DT, method="zoh")
    np.testing.assert_allclose(a_d, ref[0], rtol=EXPM_RTOL, atol=EXPM_ATOL)
    np.testing.assert_allclose(b_d, ref[1], rtol=EXPM_RTOL, atol=EXPM_ATOL)
    np.testing.assert_allclose(a_d, scipy.linalg.expm(a_c * DT), rtol=EXPM_RTOL, atol=EXPM_ATOL)


def test_zoh_singular_matrix_double_integrator():
    """Closed form for x'' = u (singular a_c): b_d = [dt^2/2, dt]."""
    a_c = jnp.array([[0.0, 1.0], [0.0, 0.0]])
    b_c = jnp.array([[0.0], [1.0]])
    dt = 0.3
    a_d, b_d = zoh(a_c, b_c, dt)
    np.testing.assert_allclose(a_d, [[1.0, dt], [0.0, 1.0]], rtol=EXPM_RTOL, atol=EXPM_ATOL)
    np.testing.assert_allclose(b_d, [[dt**2 / 2], [dt]], rtol=EXPM_RTOL, atol=EXPM_ATOL)


def test_zoh_gradient_matches_finite_differences():
    a_c, b_c = _random_system(2)

    def f(x):
        a_d, b_d = zoh(jnp.asarray(a_c).at[1, 3].set(x[0]), jnp.asarray(b_c), x[1])
        return jnp.sum(a_d**2) + jnp.sum(jnp.sin(b_d))

    assert_grad_matches_fd(f, np.array([a_c[1, 3], 0.05]), h=1e-6, rtol=1e-6)


def test_check_grads_of_zoh():
    a_c, b_c = _random_system(3)

    def discrete(x):
        a_d, b_d = zoh(jnp.asarray(a_c) * x[0], jnp.asarray(b_c), x[1])
        return jnp.concatenate([a_d.ravel(), b_d.ravel()])

    check_grads(jax.jit(discrete), (jnp.asarray([0.8, 0.05]),), order=1, modes=("fwd", "rev"), eps=1e-5)


def test_zoh_rejects_bad_shapes():
    with pytest.raises(ValueError, match="b_c must have shape"):
        zoh(jnp.eye(3), jnp.ones((2, 1)), DT)
    with pytest.raises(ValueError, match="a_c must be square"):
        zoh(jnp.ones((3, 2)), jnp.ones((3, 1)), DT)


def test_zoh_vmaps_over_dt():
    a_c, b_c = _random_system(3)
    dts = jnp.array([0.001, 0.01, 0.1])
    a_d, _ = jax.vmap(lambda dt: zoh(jnp.asarray(a_c), jnp.asarray(b_c), dt))(dts)
    for i, dt in enumerate(np.asarray(dts)):
        np.testing.assert_allclose(a_d[i], scipy.linalg.expm(a_c * dt), rtol=EXPM_RTOL, atol=EXPM_ATOL)
