"""The unbatched-under-vmap LU solve (jaxveh._linalg): the answers of NumPy, derivatives by
central differences in forward and reverse mode, and under vmap a loop of unbatched LAPACK
calls (a batched call can hang jaxlib 0.10.2's CPU thread pool)."""

import re

import jax
import jax.numpy as jnp
import numpy as np

from jaxveh._linalg import lu_factor, lu_solve

RNG = np.random.default_rng(3)
N = 6


def _general(batch=()):
    return jnp.asarray(RNG.normal(size=(*batch, N, N)) + 3.0 * np.eye(N))


def _lu(a, b):
    return lu_solve(lu_factor(a), b)


def test_solve_equals_numpy_single_and_batched():
    solve, make = _lu, _general
    m, b = make((5,)), jnp.asarray(RNG.normal(size=(5, N)))
    expected = np.linalg.solve(np.asarray(m), np.asarray(b)[..., None])[..., 0]
    np.testing.assert_allclose(solve(m[0], b[0]), expected[0], rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(jax.jit(jax.vmap(solve))(m, b), expected, rtol=1e-12, atol=1e-14)


def test_vmap_runs_unbatched_lapack_calls_in_a_loop():
    solve, make = _lu, _general
    m, b = make((4,)), jnp.asarray(RNG.normal(size=(4, N)))
    hlo = jax.jit(jax.vmap(solve)).lower(m, b).compile().as_text()
    calls = re.findall(r"= (f64\[[\d,]*\])[^\n]*custom-call\([^\n]*lapack", hlo)
    assert calls, "no LAPACK call found"
    assert all(not shape.startswith("f64[4,") for shape in calls), calls
    assert "while" in hlo


def test_lu_solve_derivatives_equal_central_differences():
    a, b = _general(), jnp.asarray(RNG.normal(size=N))
    db, w = jnp.asarray(RNG.normal(size=N)), jnp.asarray(RNG.normal(size=N))
    factors = lu_factor(a)

    def f(e):
        return jnp.sin(lu_solve(factors, b + e * db)) @ w

    h = 1e-6
    central = (f(h) - f(-h)) / (2 * h)
    np.testing.assert_allclose(jax.jvp(f, (0.0,), (1.0,))[1], central, rtol=1e-7)
    np.testing.assert_allclose(jax.grad(f)(0.0), central, rtol=1e-7)


def test_lu_solve_derivative_in_b_and_transpose():
    a, b = _general(), jnp.asarray(RNG.normal(size=N))
    factors = lu_factor(a)
    jac_fwd = jax.jacfwd(lambda x: lu_solve(factors, x))(b)
    jac_rev = jax.jacrev(lambda x: lu_solve(factors, x))(b)
    inverse = np.linalg.inv(np.asarray(a))
    np.testing.assert_allclose(jac_fwd, inverse, rtol=1e-11, atol=1e-13)
    np.testing.assert_allclose(jac_rev, inverse, rtol=1e-11, atol=1e-13)
    # no derivative with respect to the factorised matrix (stop-gradient by design)
    assert float(jnp.max(jnp.abs(jax.grad(lambda s: lu_solve(lu_factor(a * s), b).sum())(1.0)))) == 0.0
