"""Forward-difference Jacobians and Newton's method with them (jaxveh._differences): the
IMEX split's matrix and the steady-state solve's Jacobian. The car's steady states with
it: tests/test_manoeuvre_steady.py."""

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
import pytest

import jaxveh  # noqa: F401  (float64)
from jaxveh._differences import DifferenceNewton, forward_difference_jacobian


def test_forward_difference_jacobian():
    """Against the exact Jacobian of a smooth map with entries of very different sizes,
    under ``jit`` and ``vmap``; the step goes to the side it is taken on at a kink."""
    def fn(x):
        return jnp.stack([jnp.sin(x[0]) * x[1], 1e4 * x[2] ** 3 + x[0], jnp.exp(1e-3 * x[1]) - x[2]])

    def close(approx, x):
        # round-off of a forward difference: about 1e-8 of the row's value and largest slope
        exact = np.asarray(jax.jacfwd(fn)(x))
        scale = np.maximum(np.abs(exact).max(axis=1), np.abs(np.asarray(fn(x))))
        assert np.all(np.abs(np.asarray(approx) - exact) <= 1e-7 * scale[:, None])

    x = jnp.asarray([0.3, -200.0, 2.0])
    close(forward_difference_jacobian(fn, x), x)
    xs = jnp.stack([x, jnp.asarray([-1.0, 50.0, 1.5])])
    batched = jax.jit(jax.vmap(lambda xx: forward_difference_jacobian(fn, xx)))(xs)
    for k in range(2):
        close(batched[k], xs[k])
    kink = forward_difference_jacobian(lambda v: jnp.abs(v), jnp.asarray([0.0, -1.0]))
    np.testing.assert_allclose(kink, np.diag([1.0, -1.0]), rtol=1e-6)


def test_forward_difference_jacobian_skips_columns():
    """Skipped columns are zero and not evaluated (one evaluation fewer each); the others as
    without skipping; an index outside the columns is refused by name."""

    def fn(x):
        return jnp.stack([x[0] * x[1], x[1] ** 2, jnp.sin(x[2])])

    x = jnp.asarray([0.5, 2.0, 1.0])
    full = forward_difference_jacobian(fn, x)
    skipped = forward_difference_jacobian(fn, x, skip=(1,))
    np.testing.assert_array_equal(skipped[:, 1], 0.0)
    np.testing.assert_array_equal(skipped[:, [0, 2]], full[:, [0, 2]])
    lengths = [jax.make_jaxpr(lambda v, s=s: forward_difference_jacobian(fn, v, skip=s))(x).eqns
               for s in ((), (0, 2))]
    maps = [[e for e in eqns if e.primitive.name == "scan"][0].params["length"] for eqns in lengths]
    assert maps == [4, 2], maps
    with pytest.raises(ValueError, match=r"skip = \(3,\) must hold column indices in \[0, 3\)"):
        forward_difference_jacobian(fn, x, skip=(3,))


def _system(y, args):
    """Two circles' intersection plus a cubic: roots near (0.6, 0.8, 2.0)."""
    a, b, c = y
    return jnp.stack([a * a + b * b - 1.0, (a - 1.0) ** 2 + b * b - 0.8, c**3 - 8.0 + 1e-3 * a])


def test_difference_newton_converges_to_the_root_and_differentiates():
    """The root to 1e-12 against the closed form, Optimistix's Newton's root the same, and
    the root's derivative (implicit function theorem) against a central difference."""
    solver = DifferenceNewton(rtol=1e-11, atol=1e-12)
    sol = optx.root_find(_system, solver, jnp.asarray([0.5, 0.5, 1.5]), max_steps=50)
    a = 0.6  # the circles: a^2 - (a - 1)^2 = 1 - 0.8
    expected = np.asarray([a, np.sqrt(1.0 - a * a), np.cbrt(8.0 - 1e-3 * a)])
    np.testing.assert_allclose(sol.value, expected, rtol=1e-12)
    reference = optx.root_find(_system, optx.Newton(rtol=1e-11, atol=1e-12), jnp.asarray([0.5, 0.5, 1.5]))
    np.testing.assert_allclose(sol.value, reference.value, rtol=1e-12)

    def root_c(shift):
        fn = lambda y, args: _system(y, args).at[2].add(-shift)  # noqa: E731
        return optx.root_find(fn, solver, jnp.asarray([0.5, 0.5, 1.5]), max_steps=50).value[2]

    h = 1e-4
    central = (root_c(h) - root_c(-h)) / (2 * h)
    np.testing.assert_allclose(jax.grad(root_c)(0.0), central, rtol=1e-7)
    np.testing.assert_allclose(jax.grad(root_c)(0.0), 1.0 / (3.0 * expected[2] ** 2), rtol=1e-9)


def test_difference_newton_reports_a_failure():
    """No root (x^2 + 1): the solve ends unsuccessful rather than returning a number as
    converged; a NaN residual ends it at once."""
    solver = DifferenceNewton(rtol=1e-10, atol=1e-10)
    sol = optx.root_find(lambda y, args: y * y + 1.0, solver, jnp.asarray([0.3]), max_steps=30, throw=False)
    assert sol.result != optx.RESULTS.successful
    sol = optx.root_find(lambda y, args: jnp.sqrt(y - 2.0), solver, jnp.asarray([0.3]), max_steps=30, throw=False)
    assert sol.result != optx.RESULTS.successful
    assert int(sol.stats["num_steps"]) <= 2
