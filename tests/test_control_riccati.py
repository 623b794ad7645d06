"""Discrete algebraic Riccati solver against SciPy, its residual, gradients and failures."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg
from jax.test_util import check_grads

from jaxveh.control import RESULTS, riccati_residual, solve_dare, zoh

#: SciPy solves the DARE by a generalised Schur method; both are backward stable, so
#: solutions of these well-conditioned problems agree to ~1e3 eps relative.
SOLUTION_RTOL = 1e-10
#: Relative Frobenius residual of the Riccati equation at the returned solution.
RESIDUAL_TOL = 1e-12
#: Central differences with h = 1e-6 on O(1) entries: truncation + rounding ~1e-8.
FD_RTOL = 1e-6
FD_STEP = 1e-6


def _random_problem(seed, n=6, m=2):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, n))  # open-loop unstable (spectral radius > 1)
    b = rng.normal(size=(n, m))
    c = rng.normal(size=(2, n))
    q = c.T @ c + 0.1 * np.eye(n)
    r = np.diag(rng.uniform(0.5, 2.0, size=m))
    return a, b, q, r


def _double_integrator():
    """Discrete double integrator: both eigenvalues of a exactly on the unit circle."""
    a, b = zoh(jnp.array([[0.0, 1.0], [0.0, 0.0]]), jnp.array([[0.0], [1.0]]), 0.1)
    return np.asarray(a), np.asarray(b), np.diag([10.0, 0.0]), np.eye(1)


@pytest.mark.parametrize("problem", [_random_problem(0), _random_problem(1, 8, 1), _double_integrator()])
def test_matches_scipy_and_residual(problem):
    a, b, q, r = problem
    sol = solve_dare(a, b, q, r)
    reference = scipy.linalg.solve_discrete_are(a, b, q, r)
    np.testing.assert_allclose(sol.p, reference, rtol=SOLUTION_RTOL, atol=SOLUTION_RTOL * np.abs(reference).max())
    assert sol.result == RESULTS.successful
    assert float(sol.residual) < RESIDUAL_TOL
    residual = np.linalg.norm(riccati_residual(*(jnp.asarray(x) for x in problem), sol.p))
    assert residual < RESIDUAL_TOL * np.linalg.norm(reference)
    k_ref = np.linalg.solve(r + b.T @ reference @ b, b.T @ reference @ a)
    np.testing.assert_allclose(sol.k, k_ref, rtol=SOLUTION_RTOL, atol=SOLUTION_RTOL * np.abs(k_ref).max())
    assert float(sol.spectral_radius) < 1.0
    np.testing.assert_allclose(sol.spectral_radius, np.abs(np.linalg.eigvals(a - b @ k_ref)).max(), rtol=1e-9)


#: Entries perturbed in the gradient test: (input index of (a, b, q, r), entry).
GRADIENT_ENTRIES = ((0, (1, 2)), (1, (3, 1)), (2, (0, 0)), (2, (2, 4)), (3, (1, 1)))


def test_gradient_matches_finite_differences_fwd_and_rev():
    """d/dx of a weighted sum of P and K for entries of a, b, q (diagonal and off) and r."""
    base = _random_problem(0)
    weights = np.random.default_rng(7).normal(size=base[0].shape)

    @jax.jit
    def f(x):
        args = [jnp.asarray(v) for v in base]
        for value, (which, index) in zip(x, GRADIENT_ENTRIES, strict=True):
            args[which] = args[which].at[index].set(value)
        sol = solve_dare(*args)
        return jnp.sum(sol.p * weights) + jnp.sum(sol.k**2)

    x0 = jnp.array([base[which][index] for which, index in GRADIENT_ENTRIES])
    eye = np.eye(len(GRADIENT_ENTRIES))
    fd = np.array([(f(x0 + FD_STEP * e) - f(x0 - FD_STEP * e)) / (2 * FD_STEP) for e in eye])
    np.testing.assert_allclose(jax.grad(f)(x0), fd, rtol=FD_RTOL)
    np.testing.assert_allclose(jax.jacfwd(f)(x0), fd, rtol=FD_RTOL)


def test_vmap_and_vmap_of_grad():
    a, b, q, r = _random_problem(2)
    scales = jnp.array([0.5, 1.0, 2.0])
    batched = jax.vmap(lambda s: solve_dare(a, b, s * q, r).p)(scales)
    for i, s in enumerate(np.asarray(scales)):
        np.testing.assert_allclose(batched[i], scipy.linalg.solve_discrete_are(a, b, s * q, r), rtol=SOLUTION_RTOL)

    @jax.jit
    def trace_p(s):
        return jnp.trace(solve_dare(a, b, s * q, r).p)

    grads = jax.vmap(jax.grad(trace_p))(scales)
    for i, s in enumerate(np.asarray(scales)):
        fd = (trace_p(s + FD_STEP) - trace_p(s - FD_STEP)) / (2 * FD_STEP)
        np.testing.assert_allclose(grads[i], fd, rtol=FD_RTOL)


def test_check_grads_of_riccati_solution():
    """First-order derivatives of P and K (implicit function theorem) in both modes."""
    a, b, q, r = _random_problem(5, n=4, m=1)

    def solution(x):
        sol = solve_dare(jnp.asarray(a) * x[0], jnp.asarray(b), jnp.asarray(q) * x[1], jnp.asarray(r) * x[2])
        return jnp.concatenate([sol.p.ravel(), sol.k.ravel()])

    check_grads(jax.jit(solution), (jnp.asarray([0.9, 1.0, 1.5]),), order=1, modes=("fwd", "rev"), eps=1e-6, rtol=1e-5)


def test_unstabilisable_system_is_reported():
    """An unstable mode that the input cannot reach: no stabilising solution exists."""
    a = np.diag([1.5, 0.5])
    b = np.array([[0.0], [1.0]])
    sol = solve_dare(a, b, np.eye(2), np.eye(1), throw=False)
    assert sol.result != RESULTS.successful
    with pytest.raises(eqx.EquinoxRuntimeError, match="solve_dare: "):
        solve_dare(a, b, np.eye(2), np.eye(1))


def test_undetectable_marginal_mode_is_not_stabilising():
    """q = 0 on an integrator: P = 0 solves the equation but leaves |eig| = 1."""
    sol = solve_dare(np.eye(1), np.eye(1), np.zeros((1, 1)), np.eye(1), throw=False)
    assert sol.result == RESULTS.not_stabilising
    with pytest.raises(eqx.EquinoxRuntimeError, match="does not stabilise the closed loop"):
        solve_dare(np.eye(1), np.eye(1), np.zeros((1, 1)), np.eye(1))


def test_nan_input_is_reported_not_silent():
    a, b, q, r = _random_problem(3)
    a[0, 0] = np.nan
    sol = solve_dare(a, b, q, r, throw=False)
    assert sol.result == RESULTS.nonfinite


def test_no_retrace_when_values_change():
    a, b, q, r = _random_problem(4)

    @eqx.filter_jit
    @eqx.debug.assert_max_traces(max_traces=1)
    def solve(a):
        return solve_dare(a, b, q, r).p

    solve(jnp.asarray(a))
    solve(jnp.asarray(a) * 0.9)


def test_bad_shapes_raise():
    with pytest.raises(ValueError, match=r"need q \(2, 2\) and r \(1, 1\)"):
        solve_dare(np.eye(2), np.ones((2, 1)), np.eye(3), np.eye(1))
