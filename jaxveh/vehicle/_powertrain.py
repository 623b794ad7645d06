"""Powertrain (thesis section 6.1.5, "Powertrain"): a PID speed controller commanding the
drive torque of the rear wheels through an open differential.

The thesis uses "a simplified PID controller capable of controlling the torque applied to
the rear driving wheels". Here, as a force element:

- speed ``u``: the velocity of a chassis point along the chassis x axis (m/s);
- error ``e = v_ref(t) - u``; derivative from a first-order filter of the speed (state
  ``x_f``, ``x_f_dot = (u - x_f) / tau``, so ``e_dot ≈ -(u - x_f) / tau``); integral state
  with conditional anti-windup (it stops integrating while the torque is saturated in the
  direction the error pushes);
- torque ``T = clip(kp e + ki ∫e + kd e_dot, t_min, t_max)`` (N m; negative brakes);
- open differential (documented choice): ``T / 2`` on each driven wheel about its spin axis,
  the reaction ``-T / 2`` about the same axes on the chassis (an inboard differential), so
  the element's torques sum to zero.
"""

import abc

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import check_range, float_field, is_concrete
from ..multibody import AbstractForceElement, ElementForces, zero_forces

#: The powertrain's auxiliary states: speed-error integral (m) and filtered speed (m/s).
POWERTRAIN_STATES = ("powertrain.integral", "powertrain.speed_filter")


class AbstractSpeedTarget(eqx.Module):
    """Target speed ``v_ref(t)`` (m/s)."""

    @abc.abstractmethod
    def __call__(self, t):
        """Target speed at time ``t`` (s)."""


class ConstantSpeed(AbstractSpeedTarget):
    speed: Float[Array, ""] = float_field()

    def __call__(self, t):
        return self.speed + jnp.zeros_like(t)


class SpeedPID(eqx.Module):
    """PID gains ``kp`` (N m per m/s), ``ki`` (N m per m), ``kd`` (N m per m/s²), speed filter
    time constant ``tau`` (s, > 0), torque limits ``t_min`` <= 0 <= ``t_max`` (N m)."""

    kp: Float[Array, ""] = float_field()
    ki: Float[Array, ""] = float_field()
    kd: Float[Array, ""] = float_field(default=0.0)
    tau: Float[Array, ""] = float_field(default=0.02)
    t_min: Float[Array, ""] = float_field(default=-1e4)
    t_max: Float[Array, ""] = float_field(default=1e4)

    def __check_init__(self):
        limits = {"kp": {"low": 0.0}, "ki": {"low": 0.0}, "kd": {"low": 0.0}, "tau": {"low": 0.0, "low_open": True},
                  "t_min": {"high": 0.0}, "t_max": {"low": 0.0}}
        for name, bounds in limits.items():
            if is_concrete(getattr(self, name)):  # traced gains are the optimiser's business
                check_range(name, getattr(self, name), **bounds)

    def torque(self, error, integral, error_rate):
        """``(saturated torque, unsaturated torque)`` (N m)."""
        raw = self.kp * error + self.ki * integral + self.kd * error_rate
        return jnp.clip(raw, self.t_min, self.t_max), raw


class Powertrain(AbstractForceElement):
    """PID speed control of the drive torque through an open differential (see module).
    Static point indices: ``speed_point`` (on the chassis, body ``chassis``), ``wheels``
    (one point on each driven wheel body), ``reaction`` (a chassis point)."""

    chassis: int = eqx.field(static=True)
    speed_point: int = eqx.field(static=True)
    wheels: tuple[int, ...] = eqx.field(static=True)
    reaction: int = eqx.field(static=True)
    pid: SpeedPID
    target: AbstractSpeedTarget
    aux_names: tuple[str, ...] = eqx.field(static=True, default=POWERTRAIN_STATES)

    @classmethod
    def on(cls, system, chassis: str, speed_point: str, wheels, reaction: str, pid: SpeedPID,
           target: AbstractSpeedTarget) -> "Powertrain":
        """Build from names; ``wheels``: the driven wheels' points."""
        return cls(system.body_names.index(chassis), system.point_index(speed_point),
                   tuple(system.point_index(w) for w in wheels), system.point_index(reaction), pid, target)

    def speed(self, kin):
        return jnp.dot(kin.rotations[self.chassis][:, 0], kin.xd[self.speed_point])

    def control(self, kin, aux):
        """``(torque, integral rate, filter rate)``."""
        u = self.speed(kin)
        error = self.target(kin.t) - u
        filter_rate = (u - aux[1]) / self.pid.tau
        torque, raw = self.pid.torque(error, aux[0], -filter_rate)
        winding = (raw != torque) & (jnp.sign(error) == jnp.sign(raw))
        return torque, jnp.where(winding, 0.0, error), filter_rate

    def __call__(self, kin, aux, system):
        torque, integral_rate, filter_rate = self.control(kin, aux)
        w = np.asarray(self.wheels, int)
        axes = kin.point_rotations[w][:, :, 1]
        share = torque / len(self.wheels)
        out = zero_forces(kin, 2)
        torques = out.torques.at[w].add(share * axes).at[self.reaction].add(-share * jnp.sum(axes, axis=0))
        return ElementForces(forces=out.forces, torques=torques, aux_dot=jnp.stack([integral_rate, filter_rate]))
