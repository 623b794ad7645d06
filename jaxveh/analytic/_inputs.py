"""Steering inputs: road-wheel steer angle δ(t) (rad) as Equinox modules."""

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..params import Range, checked_field


class AbstractSteer(eqx.Module):
    """A road-wheel steer angle history δ(t) in rad."""

    @abc.abstractmethod
    def __call__(self, t) -> Float[Array, ""]:
        """Steer angle (rad) at time ``t`` (s)."""


class ConstantSteer(AbstractSteer):
    """δ(t) = angle (rad)."""

    angle: Float[Array, ""] = checked_field("ConstantSteer.angle", Range(what="road-wheel steer angle, rad"))

    def __call__(self, t):
        return self.angle + 0.0 * t


class SmoothStep(AbstractSteer):
    """Cubic smoothed step: 0 before ``start``, ``amplitude`` after ``start + rise`` (rad, s).

    δ = A (3 s^2 - 2 s^3), s = (t - start)/rise clipped to [0, 1]: continuous first
    derivative, as in section 3.3.3. ``rise`` must be > 0 (it divides), the others not NaN;
    checked on construction (``ParameterError``; traced values: ``eqx.error_if``).
    """

    amplitude: Float[Array, ""] = checked_field("SmoothStep.amplitude", Range(what="steer amplitude, rad"))
    start: Float[Array, ""] = checked_field("SmoothStep.start", Range(what="start time, s"))
    rise: Float[Array, ""] = checked_field("SmoothStep.rise", Range(0.0, low_open=True, what="rise time, s"))

    def __call__(self, t):
        s = jnp.clip((t - self.start) / self.rise, 0.0, 1.0)
        return self.amplitude * s * s * (3.0 - 2.0 * s)
