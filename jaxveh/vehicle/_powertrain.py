"""Powertrain (thesis section 6.1.5, "Powertrain"): a PID speed controller commanding the
drive torque of the rear wheels through an open differential, and the brakes.

The thesis uses "a simplified PID controller capable of controlling the torque applied to
the rear driving wheels". Here, as a force element:

- speed ``u``: the velocity of a chassis point along the chassis x axis (m/s);
- error ``e = v_ref(t) - u``; derivative from a first-order filter of the speed (state
  ``x_f``, ``x_f_dot = (u - x_f) / tau``, so ``e_dot ≈ -(u - x_f) / tau``); integral state
  with conditional anti-windup (it stops integrating while the torque is saturated in the
  direction the error pushes);
- feedforward of the target's acceleration (beyond the thesis): ``T_ff = k_ff dv_ref/dt``,
  ``k_ff`` the torque that accelerates the car's mass at the wheels' radius (``car_elements``
  sets it), so a speed ramp is followed without the PI loop's lag; zero at constant speed;
- torque ``T = clip(kp e + ki ∫e + kd e_dot + T_ff, t_min, t_max)`` (N m; negative brakes);
- open differential (documented choice): ``max(T, 0) / 2`` on each driven wheel about its
  spin axis, the reaction about the same axes on the chassis (an inboard differential);
- brakes (beyond the thesis): ``min(T, 0)`` on all four wheels, the front axle's share
  ``SpeedPID.brake_front_share`` split equally between its wheels, the rest on the rear
  wheels; each brake's reaction acts on its upright (outboard brakes). Without braked wheels
  (a bare rig) a negative torque goes through the differential like a positive one.

The element's torques sum to zero.
"""

import abc

import equinox as eqx
import jax
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

    def acceleration(self, t):
        """``dv_ref/dt`` (m/s^2) at time ``t`` (s), by forward-mode autodiff of the target."""
        t = jnp.asarray(t, jnp.float64)
        return jax.jvp(self.__call__, (t,), (jnp.ones_like(t),))[1]

    def kinks(self) -> tuple:
        """Times (s) where a derivative of the target jumps (none by default)."""
        return ()


class ConstantSpeed(AbstractSpeedTarget):
    speed: Float[Array, ""] = float_field()

    def __call__(self, t):
        return self.speed + jnp.zeros_like(t)


class SpeedChange(AbstractSpeedTarget):
    """A change of speed from ``speed`` to ``final_speed`` (m/s, > 0) at ``rate`` (m/s^2, >
    0) starting at ``start`` (s): the target's acceleration rises linearly to ``rate`` (with
    the sign of the change) over ``rise`` seconds, holds, and falls back to zero over
    ``rise`` seconds, so that the target's speed is continuous with a continuous rate. It
    holds ``speed`` before and ``final_speed`` after (a change shorter than ``rise`` at full
    rate never reaches ``rate``)."""

    speed: Float[Array, ""] = float_field()
    final_speed: Float[Array, ""] = float_field()
    rate: Float[Array, ""] = float_field()
    start: Float[Array, ""] = float_field(default=0.5)
    rise: Float[Array, ""] = float_field(default=0.2)

    def __check_init__(self):
        limits = {"speed": {"low": 0.0, "low_open": True, "what": "m/s"},
                  "final_speed": {"low": 0.0, "low_open": True, "what": "m/s"},
                  "rate": {"low": 0.0, "low_open": True, "what": "m/s^2"}, "start": {"low": 0.0, "what": "s"},
                  "rise": {"low": 0.0, "low_open": True, "what": "s"}}
        for name, bounds in limits.items():
            if is_concrete(getattr(self, name)):
                check_range(f"SpeedChange.{name}", getattr(self, name), **bounds)

    def change_time(self):
        """Time (s) from ``start`` to the end of the hold at ``rate``: ``|final_speed - speed| / rate``."""
        return jnp.abs(self.final_speed - self.speed) / self.rate

    def __call__(self, t):
        def ramp_integral(x):  # twice-integrated unit step
            return 0.5 * jnp.maximum(x, 0.0) ** 2

        t1 = self.start + self.change_time()
        s = t - self.start
        area = (ramp_integral(s) - ramp_integral(s - self.rise) - ramp_integral(t - t1)
                + ramp_integral(t - t1 - self.rise))
        return self.speed + jnp.sign(self.final_speed - self.speed) * self.rate / self.rise * area

    def kinks(self):
        t1 = self.start + self.change_time()
        return (self.start, self.start + self.rise, t1, t1 + self.rise)


class SpeedPID(eqx.Module):
    """PID gains ``kp`` (N m per m/s), ``ki`` (N m per m), ``kd`` (N m per m/s²), speed filter
    time constant ``tau`` (s, > 0), torque limits ``t_min`` <= 0 <= ``t_max`` (N m; a
    negative torque brakes) and the front axle's share of the brake torque
    ``brake_front_share`` (in [0, 1])."""

    kp: Float[Array, ""] = float_field()
    ki: Float[Array, ""] = float_field()
    kd: Float[Array, ""] = float_field(default=0.0)
    tau: Float[Array, ""] = float_field(default=0.02)
    t_min: Float[Array, ""] = float_field(default=-1e4)
    t_max: Float[Array, ""] = float_field(default=1e4)
    brake_front_share: Float[Array, ""] = float_field(default=0.65)

    def __check_init__(self):
        self.check()

    def check(self, prefix: str = "") -> None:
        """Refuse concrete values out of range, naming ``prefix`` + the field (traced gains
        are the optimiser's business)."""
        limits = {"kp": {"low": 0.0}, "ki": {"low": 0.0}, "kd": {"low": 0.0}, "tau": {"low": 0.0, "low_open": True},
                  "t_min": {"high": 0.0}, "t_max": {"low": 0.0}, "brake_front_share": {"low": 0.0, "high": 1.0}}
        for name, bounds in limits.items():
            if is_concrete(getattr(self, name)):
                check_range(prefix + name, getattr(self, name), **bounds)

    def torque(self, error, integral, error_rate, feedforward=0.0):
        """``(saturated torque, unsaturated torque)`` (N m), ``feedforward`` (N m) added."""
        raw = self.kp * error + self.ki * integral + self.kd * error_rate + feedforward
        return jnp.clip(raw, self.t_min, self.t_max), raw


class Powertrain(AbstractForceElement):
    """PID speed control of the drive torque through an open differential, and the brakes
    (see module). Static point indices: ``speed_point`` (on the chassis, body ``chassis``),
    ``wheels`` (one point on each driven wheel body), ``reaction`` (a chassis point),
    ``brake_wheels`` (one point on each braked wheel body), ``brake_mounts`` (a point on the
    body that carries each brake) and ``brake_front`` (whether each braked wheel is on the
    front axle). ``feedforward``: N m per m/s^2 of the target's acceleration."""

    chassis: int = eqx.field(static=True)
    speed_point: int = eqx.field(static=True)
    wheels: tuple[int, ...] = eqx.field(static=True)
    reaction: int = eqx.field(static=True)
    pid: SpeedPID
    target: AbstractSpeedTarget
    brake_wheels: tuple[int, ...] = eqx.field(static=True, default=())
    brake_mounts: tuple[int, ...] = eqx.field(static=True, default=())
    brake_front: tuple[bool, ...] = eqx.field(static=True, default=())
    feedforward: Float[Array, ""] = float_field(default=0.0)
    aux_names: tuple[str, ...] = eqx.field(static=True, default=POWERTRAIN_STATES)

    def __check_init__(self):
        if not len(self.brake_wheels) == len(self.brake_mounts) == len(self.brake_front):
            raise ValueError("brake_wheels, brake_mounts and brake_front need one entry per braked wheel")
        if self.brake_wheels and not (any(self.brake_front) and not all(self.brake_front)):
            raise ValueError("brakes need at least one front and one rear wheel (brake_front)")

    @classmethod
    def on(cls, system, chassis: str, speed_point: str, wheels, reaction: str, pid: SpeedPID,
           target: AbstractSpeedTarget, brakes=(), feedforward=0.0) -> "Powertrain":
        """Build from names; ``wheels``: the driven wheels' points; ``brakes``: ``(wheel
        point, mount point, front)`` per braked wheel."""
        return cls(system.body_names.index(chassis), system.point_index(speed_point),
                   tuple(system.point_index(w) for w in wheels), system.point_index(reaction), pid, target,
                   tuple(system.point_index(b[0]) for b in brakes), tuple(system.point_index(b[1]) for b in brakes),
                   tuple(bool(b[2]) for b in brakes), feedforward)

    def speed(self, kin):
        return jnp.dot(kin.rotations[self.chassis][:, 0], kin.xd[self.speed_point])

    def control(self, kin, aux):
        """``(torque, integral rate, filter rate)``."""
        u = self.speed(kin)
        error = self.target(kin.t) - u
        filter_rate = (u - aux[1]) / self.pid.tau
        torque, raw = self.pid.torque(error, aux[0], -filter_rate, self.feedforward * self.target.acceleration(kin.t))
        winding = (raw != torque) & (jnp.sign(error) == jnp.sign(raw))
        return torque, jnp.where(winding, 0.0, error), filter_rate

    def split(self, torque):
        """``(drive, brake)``: the torque (N m) on each driven wheel and on each braked wheel
        about its spin axis (negative brakes; see module)."""
        if not self.brake_wheels:
            return jnp.full(len(self.wheels), torque / len(self.wheels)), jnp.zeros(0)
        front = self.pid.brake_front_share
        n_front = sum(self.brake_front)
        shares = jnp.stack([front / n_front if f else (1.0 - front) / (len(self.brake_front) - n_front)
                            for f in self.brake_front])
        drive = jnp.full(len(self.wheels), jnp.maximum(torque, 0.0) / len(self.wheels))
        return drive, jnp.minimum(torque, 0.0) * shares

    def __call__(self, kin, aux, system):
        torque, integral_rate, filter_rate = self.control(kin, aux)
        drive, brake = self.split(torque)
        w = np.asarray(self.wheels, int)
        axes = drive[:, None] * kin.point_rotations[w][:, :, 1]
        out = zero_forces(kin, 2)
        torques = out.torques.at[w].add(axes).at[self.reaction].add(-jnp.sum(axes, axis=0))
        if self.brake_wheels:
            b, m = np.asarray(self.brake_wheels, int), np.asarray(self.brake_mounts, int)
            axes = brake[:, None] * kin.point_rotations[b][:, :, 1]
            torques = torques.at[b].add(axes).at[m].add(-axes)
        return ElementForces(forces=out.forces, torques=torques, aux_dot=jnp.stack([integral_rate, filter_rate]))
