"""The unbatched-under-vmap LU solve (jaxveh._linalg): the answers of NumPy, derivatives by
central differences in forward and reverse mode, and under vmap a loop of unbatched LAPACK
calls (a batched call can hang jaxlib 0.10.2's CPU thread pool). The shifted solves of the
IMEX stages: LU unbatched, the spectral form's products under vmap, LU where a member's
spectral form is refused."""

import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh._linalg import lu_factor, lu_solve, shifted_factor, shifted_solve, spectral_form

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


# ---- shifted systems (I - s A) x = b: LU unbatched, the spectral form under vmap ----------


def _shifted(a, shift, b):
    factors = shifted_factor(a, spectral_form(a), shift)
    return shifted_solve(factors, b)


def _shifted_expected(a, shift, b, transposed=False):
    m = np.eye(N) - np.asarray(shift)[..., None, None] * np.asarray(a)
    if transposed:
        m = np.swapaxes(m, -1, -2)
    return np.linalg.solve(m, np.asarray(b)[..., None])[..., 0]


def test_shifted_solve_equals_numpy_single_and_batched():
    a, b = jnp.asarray(RNG.normal(size=(5, N, N))), jnp.asarray(RNG.normal(size=(5, N)))
    shift = jnp.asarray(RNG.uniform(0.01, 0.5, size=5))
    expected = _shifted_expected(a, shift, b)
    np.testing.assert_allclose(jax.jit(_shifted)(a[0], shift[0], b[0]), expected[0], rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(jax.jit(jax.vmap(_shifted))(a, shift, b), expected, rtol=1e-11, atol=1e-12)
    # one matrix for the batch, many shifts: the unbatched matrix has no spectral form, LU solves
    np.testing.assert_allclose(jax.jit(jax.vmap(_shifted, in_axes=(None, 0, 0)))(a[0], shift, b),
                               _shifted_expected(a[0], shift, b), rtol=1e-12, atol=1e-13)


def test_spectral_form_only_under_vmap_and_checked():
    """The spectral form is computed where the program is batched (unbatched: empty, not
    usable) and refused for a defective matrix (a Jordan block), whose member the batch then
    solves by LU, to round-off."""
    a = jnp.asarray(RNG.normal(size=(3, N, N)))
    assert not bool(jax.jit(spectral_form)(a[0]).usable)
    assert np.all(jax.jit(jax.vmap(spectral_form))(a).usable)
    jordan = a.at[1].set(jnp.zeros((N, N)).at[0, 1].set(1.0))
    assert list(np.asarray(jax.jit(jax.vmap(spectral_form))(jordan).usable)) == [True, False, True]
    shift, b = jnp.asarray([0.1, 0.2, 0.3]), jnp.asarray(RNG.normal(size=(3, N)))
    np.testing.assert_allclose(jax.jit(jax.vmap(_shifted))(jordan, shift, b), _shifted_expected(jordan, shift, b),
                               rtol=1e-12, atol=1e-13)


def test_batched_shifted_solve_is_matrix_vector_products():
    """Under vmap with usable spectral forms the stage solves are products, with the LU loop
    kept behind a branch; no batched LAPACK call anywhere (the thread-pool hang)."""
    a, b = jnp.asarray(RNG.normal(size=(4, N, N))), jnp.asarray(RNG.normal(size=(4, N)))
    shift = jnp.full(4, 0.1)
    hlo = jax.jit(jax.vmap(_shifted)).lower(a, shift, b).compile().as_text()
    calls = re.findall(r"= \(?(\w+\[[\d,]*\])[^\n]*custom-call\([^\n]*lapack", hlo)
    assert calls, "no LAPACK call found"
    assert all(not re.match(r"\w+\[4,", s) for s in calls), calls
    assert "conditional" in hlo


@pytest.mark.parametrize("batched", [False, True])
def test_shifted_solve_derivatives(batched):
    """Forward and reverse mode in ``b`` are the solve and its transpose (the inverse matrix
    and its transpose); nothing flows to the matrix or the shift."""
    a, b = jnp.asarray(RNG.normal(size=(3, N, N))), jnp.asarray(RNG.normal(size=(3, N)))
    shift = jnp.asarray([0.05, 0.2, 0.4])
    inverse = np.linalg.inv(np.eye(N) - np.asarray(shift)[:, None, None] * np.asarray(a))

    def jacobians(a, s, x):
        solve = lambda y: _shifted(a, s, y)  # noqa: E731
        return jax.jacfwd(solve)(x), jax.jacrev(solve)(x)

    if batched:
        fwd, rev = jax.jit(jax.vmap(jacobians))(a, shift, b)
    else:
        fwd, rev = zip(*(jax.jit(jacobians)(a[k], shift[k], b[k]) for k in range(3)))
    np.testing.assert_allclose(np.asarray(fwd), inverse, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(np.asarray(rev), inverse, rtol=1e-10, atol=1e-12)
    grads = jax.grad(lambda m, s: _shifted(m, s, b[0]).sum(), argnums=(0, 1))(a[0], shift[0])
    assert all(float(jnp.max(jnp.abs(g))) == 0.0 for g in grads)
