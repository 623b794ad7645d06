"""Shared test utilities."""

import jax
import jax.numpy as jnp
import numpy as np


def central_difference(f, x, h):
    """Central finite difference of scalar ``f`` at array ``x`` (same shape as x)."""
    x = np.asarray(x, dtype=np.float64)
    grad = np.zeros_like(x)
    for i in np.ndindex(x.shape):
        step = np.zeros_like(x)
        step[i] = h
        grad[i] = (float(f(jnp.asarray(x + step))) - float(f(jnp.asarray(x - step)))) / (2 * h)
    return grad


def assert_grad_matches_fd(f, x, h=1e-6, rtol=1e-5, atol=1e-8):
    """Assert ``jax.grad(f)(x)`` equals a central finite difference."""
    g = np.asarray(jax.grad(f)(jnp.asarray(x, dtype=jnp.float64)))
    fd = central_difference(f, x, h)
    np.testing.assert_allclose(g, fd, rtol=rtol, atol=atol)
