"""The fused trigonometric functions (jaxveh._trig) against NumPy's, their symmetries and
their derivatives against the closed forms and central differences."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh  # noqa: F401  (float64)
from jaxveh import _trig as trig

RNG = np.random.default_rng(7)


def ulps(value, reference):
    """Largest difference in units of the reference's last place."""
    value, reference = np.asarray(value), np.asarray(reference)
    return float(np.max(np.abs(value - reference) / np.spacing(np.maximum(np.abs(reference), 1e-300))))


@pytest.mark.parametrize("scale", [1e-9, 0.5, 3.0, 100.0, 1e4, 1e7])
def test_sin_cos_match_numpy(scale):
    x = RNG.uniform(-scale, scale, 20000)
    s, c = jax.jit(trig.sin_cos)(x)
    assert ulps(s, np.sin(x)) <= 4 and ulps(c, np.cos(x)) <= 4
    assert np.max(np.abs(s - np.sin(x))) <= 2.3e-16 and np.max(np.abs(c - np.cos(x))) <= 2.3e-16


def test_reduction_near_multiples_of_half_pi():
    """Arguments next to k pi / 2, where the reduction cancels most digits."""
    k = np.arange(-2000, 2001)
    x = np.concatenate([k * (np.pi / 2), np.nextafter(k * (np.pi / 2), np.inf)])
    s, c = jax.jit(trig.sin_cos)(x)
    assert np.max(np.abs(s - np.sin(x))) <= 2.3e-16 and np.max(np.abs(c - np.cos(x))) <= 2.3e-16


def test_inverse_functions_match_numpy():
    for scale in (1e-6, 0.3, 1.0, 30.0, 1e8):
        x = RNG.uniform(-scale, scale, 20000)
        assert ulps(jax.jit(trig.arctan)(x), np.arctan(x)) <= 4
    y, x = RNG.normal(size=(2, 20000))
    assert ulps(jax.jit(trig.arctan2)(y, x), np.arctan2(y, x)) <= 4
    u = RNG.uniform(-1.0, 1.0, 20000)
    assert ulps(jax.jit(trig.arcsin)(u), np.arcsin(u)) <= 6
    assert ulps(jax.jit(trig.arccos)(u), np.arccos(u)) <= 6
    t = RNG.uniform(-1.5, 1.5, 20000)
    assert ulps(jax.jit(trig.tan)(t), np.tan(t)) <= 6


def test_special_values():
    ys = np.array([0.0, 0.0, -0.0, 1.0, -1.0, 0.0, 2.0])
    xs = np.array([0.0, -1.0, -1.0, 0.0, 0.0, 3.0, -2.0])
    np.testing.assert_array_equal(trig.arctan2(ys, xs), np.arctan2(ys, xs))
    ends = np.array([-1.0, 0.0, 1.0])
    np.testing.assert_array_equal(trig.arccos(ends), np.arccos(ends))
    np.testing.assert_array_equal(trig.arcsin(ends), np.arcsin(ends))
    np.testing.assert_array_equal(trig.arctan(np.array([np.inf, -np.inf, 0.0])), np.arctan([np.inf, -np.inf, 0.0]))
    assert np.isnan(trig.sin(jnp.nan)) and np.isnan(trig.arctan(jnp.nan))
    assert trig.sin(3).dtype == jnp.float64  # integers are taken as float64


def test_symmetries_are_exact():
    x = RNG.uniform(0.0, 50.0, 5000)
    s, c = trig.sin_cos(x)
    sm, cm = trig.sin_cos(-x)
    np.testing.assert_array_equal(sm, -s)
    np.testing.assert_array_equal(cm, c)
    np.testing.assert_array_equal(trig.arctan(-x), -trig.arctan(x))
    y = RNG.normal(size=5000)
    np.testing.assert_array_equal(trig.arctan2(-y, x), -trig.arctan2(y, x))


def test_derivatives_are_the_closed_forms():
    x = jnp.asarray(RNG.uniform(-4.0, 4.0, 50))
    u = jnp.asarray(RNG.uniform(-0.95, 0.95, 50))
    y = jnp.asarray(RNG.normal(size=50))
    grad = jax.vmap(jax.grad(trig.sin))
    np.testing.assert_allclose(grad(x), np.cos(x), rtol=0, atol=1e-15)
    np.testing.assert_allclose(jax.vmap(jax.grad(trig.cos))(x), -np.sin(x), rtol=0, atol=1e-15)
    np.testing.assert_allclose(jax.vmap(jax.grad(jax.grad(trig.sin)))(x), -np.sin(x), rtol=0, atol=1e-15)
    np.testing.assert_allclose(jax.vmap(jax.grad(trig.tan))(u), 1.0 / np.cos(u) ** 2, rtol=1e-14)
    np.testing.assert_allclose(jax.vmap(jax.grad(trig.arctan))(x), 1.0 / (1.0 + x**2), rtol=1e-15)
    np.testing.assert_allclose(jax.vmap(jax.grad(trig.arcsin))(u), 1.0 / np.sqrt(1.0 - u**2), rtol=1e-14)
    np.testing.assert_allclose(jax.vmap(jax.grad(trig.arccos))(u), -1.0 / np.sqrt(1.0 - u**2), rtol=1e-14)
    dy, dx = jax.vmap(jax.grad(trig.arctan2, argnums=(0, 1)))(y, x)
    np.testing.assert_allclose(dy, x / (x**2 + y**2), rtol=1e-14)
    np.testing.assert_allclose(dx, -y / (x**2 + y**2), rtol=1e-14)


@pytest.mark.parametrize("name", ["sin", "cos", "tan", "arctan", "arcsin", "arccos"])
def test_derivatives_against_central_differences(name):
    f = getattr(trig, name)
    x = jnp.asarray([-0.7, -0.2, 0.1, 0.45, 0.8])
    h = 1e-6
    central = (f(x + h) - f(x - h)) / (2 * h)
    np.testing.assert_allclose(jax.vmap(jax.grad(f))(x), central, rtol=1e-8, atol=1e-10)
    # forward mode agrees with reverse mode
    np.testing.assert_allclose(jax.jvp(f, (x,), (jnp.ones_like(x),))[1], jax.vmap(jax.grad(f))(x), rtol=1e-15)
