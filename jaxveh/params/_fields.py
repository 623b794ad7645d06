"""Field helpers for parameter modules: every physical number is a float64 array leaf."""

import equinox as eqx
import jax.numpy as jnp


def as_float(x):
    """Convert to a float64 array (keeps tracers; a new value never retraces)."""
    return jnp.asarray(x, dtype=jnp.float64)


def float_field(**kwargs):
    """An Equinox field converted to a float64 array on construction."""
    return eqx.field(converter=as_float, **kwargs)
