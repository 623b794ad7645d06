"""Spring-damper force laws (thesis eq. 6.10, ``F = F(l_s, l_s_dot)`` from look-up tables).

A :class:`SpringDamperLaw` is the sum of a spring table (force vs length), a damper table
(force vs rate) and a bump stop, the force positive in compression (it pushes the ends
apart). Tables are piecewise linear between their points and continue with their end slopes
beyond them (a spring does not saturate at the last measured point). The bump stop engages
below ``bump_stop_length`` with rate ``bump_stop_rate``, rounded over ``BUMP_STOP_ROUNDING``
so the force stays smooth for the integrator and for gradients.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import ParameterError, check_range, float_field, is_concrete

#: Length (m) over which the bump stop's force rises from zero to its linear law.
BUMP_STOP_ROUNDING = 1e-3


def interpolate(x, xs, ys):
    """Piecewise-linear ``y(x)`` through ``(xs, ys)`` (``xs`` increasing), continued with the
    end slopes outside ``[xs[0], xs[-1]]``. The interval is found by comparing ``x`` with
    every knot (one fused operation; ``jnp.interp``'s search compiles to a loop)."""
    n = xs.shape[0]
    x = jnp.asarray(x)
    knots = jnp.reshape(xs, (1,) * x.ndim + (n,))
    i = jnp.clip(jnp.sum(x[..., None] >= knots, axis=-1), 1, n - 1)
    inside = ys[i - 1] + (x - xs[i - 1]) / (xs[i] - xs[i - 1]) * (ys[i] - ys[i - 1])
    low = ys[0] + (x - xs[0]) * (ys[1] - ys[0]) / (xs[1] - xs[0])
    high = ys[-1] + (x - xs[-1]) * (ys[-1] - ys[-2]) / (xs[-1] - xs[-2])
    return jnp.where(x < xs[0], low, jnp.where(x > xs[-1], high, inside))


def _check_table(name: str, xs, ys, unit: str):
    if xs.ndim != 1 or xs.shape != ys.shape or xs.shape[0] < 2:
        raise ParameterError(f"{name}: needs two 1-D tables of equal length >= 2, got shapes {xs.shape}, {ys.shape}")
    if is_concrete(xs):
        d = np.diff(np.asarray(xs))
        if not np.all(np.isfinite(np.asarray(xs))) or not np.all(d > 0):
            raise ParameterError(
                f"{name}: the {unit} column must be finite and strictly increasing, got {np.asarray(xs)}"
            )
    if is_concrete(ys) and not np.all(np.isfinite(np.asarray(ys))):
        raise ParameterError(f"{name}: forces must be finite, got {np.asarray(ys)}")


class SpringDamperLaw(eqx.Module):
    """``F(l, l_dot)`` (N, positive in compression): spring table ``spring_length`` (m,
    increasing) -> ``spring_force`` (N), damper table ``damper_rate`` (m/s, increasing;
    negative in compression) -> ``damper_force`` (N), bump stop below ``bump_stop_length``
    (m) at ``bump_stop_rate`` (N/m; 0 for none)."""

    spring_length: Float[Array, " n"] = float_field()
    spring_force: Float[Array, " n"] = float_field()
    damper_rate: Float[Array, " k"] = float_field()
    damper_force: Float[Array, " k"] = float_field()
    bump_stop_length: Float[Array, ""] = float_field(default=0.0)
    bump_stop_rate: Float[Array, ""] = float_field(default=0.0)

    def __check_init__(self):
        _check_table("spring table", self.spring_length, self.spring_force, "length")
        _check_table("damper table", self.damper_rate, self.damper_force, "rate")
        if is_concrete(self.bump_stop_rate):
            check_range("bump_stop_rate", self.bump_stop_rate, low=0.0, what="N/m")

    def spring(self, length):
        return interpolate(length, self.spring_length, self.spring_force)

    def damper(self, rate):
        return interpolate(rate, self.damper_rate, self.damper_force)

    def bump_stop(self, length):
        r = BUMP_STOP_ROUNDING
        return self.bump_stop_rate * r * jax.nn.softplus((self.bump_stop_length - length) / r)

    def __call__(self, length, rate):
        return self.spring(length) + self.damper(rate) + self.bump_stop(length)


def linear_spring_damper(rate, free_length, damping, bump_stop_length=0.0, bump_stop_rate=0.0) -> SpringDamperLaw:
    """The linear law ``k (l0 - l) - c l_dot`` (+ bump stop): spring rate ``k`` (N/m, > 0),
    free length ``l0`` (m, > 0), damping ``c`` (N s/m, >= 0)."""
    rate = check_range("rate", rate, low=0.0, low_open=True, what="N/m")
    free_length = check_range("free_length", free_length, low=0.0, low_open=True, what="m")
    damping = check_range("damping", damping, low=0.0, what="N s/m")
    return SpringDamperLaw(
        spring_length=jnp.stack([jnp.zeros_like(free_length), free_length]),
        spring_force=jnp.stack([rate * free_length, jnp.zeros_like(rate)]),
        damper_rate=jnp.asarray([-1.0, 1.0]),
        damper_force=jnp.stack([damping, -damping]),
        bump_stop_length=bump_stop_length,
        bump_stop_rate=bump_stop_rate,
    )
