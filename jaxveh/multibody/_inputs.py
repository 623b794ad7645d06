"""Rheonomic inputs (e.g. the steering-rack travel): open-loop functions of time, or
closed-loop laws of the state.

An input law gives the values ``u`` (m or rad) and their rates ``u_dot`` as functions of
``(t, q, aux)``. The rates may not depend on the independent velocities ``z``: ``u_dot``
is needed before the velocities can be recovered (it enters ``b = -Phi_u u_dot``), and the
accelerations ``u_ddot`` are taken exactly by differentiating ``u_dot`` along
``(1, q_dot, aux_dot)``. A driver that reacts to velocities does so through an auxiliary
state (an actuator or filter), as a real steering system does.
"""

import abc
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float


class AbstractInputs(eqx.Module):
    """Values and rates of the rheonomic inputs of a system."""

    @abc.abstractmethod
    def value(self, t, q, aux) -> Float[Array, " ni"]:
        """Input values at time ``t`` (s) and state ``(q, aux)``."""

    @abc.abstractmethod
    def rate(self, t, q, aux) -> Float[Array, " ni"]:
        """Their time derivatives (independent of the velocities ``z``)."""


class TimeInputs(AbstractInputs):
    """Open-loop inputs ``u = fn(t)``; the rate is ``d fn / dt`` by forward-mode autodiff."""

    fn: Callable

    def value(self, t, q, aux):
        del q, aux
        return jnp.atleast_1d(jnp.asarray(self.fn(t), jnp.float64))

    def rate(self, t, q, aux):
        del q, aux
        return jax.jvp(lambda tt: jnp.atleast_1d(jnp.asarray(self.fn(tt), jnp.float64)), (t,), (jnp.ones_like(t),))[1]


class StateInputs(AbstractInputs):
    """Closed-loop inputs: ``value_fn(t, q, aux)`` and ``rate_fn(t, q, aux)`` supplied by the
    user (they must be consistent: ``rate`` is the time derivative of ``value`` along the
    motion). Typical use: the rack position is an auxiliary state of a driver element,
    ``value = aux[k]`` and ``rate`` = that element's state derivative written in ``(t, q, aux)``."""

    value_fn: Callable
    rate_fn: Callable

    def value(self, t, q, aux):
        return jnp.atleast_1d(self.value_fn(t, q, aux))

    def rate(self, t, q, aux):
        return jnp.atleast_1d(self.rate_fn(t, q, aux))


def as_inputs(inputs) -> AbstractInputs | None:
    """Accept an input law, a plain function of time (wrapped as :class:`TimeInputs`) or None."""
    if inputs is None or isinstance(inputs, AbstractInputs):
        return inputs
    if callable(inputs):
        return TimeInputs(inputs)
    raise TypeError(f"inputs must be a function of time or an AbstractInputs law, got {type(inputs).__name__}")
