"""Closed-loop driver (section 6.1.5 "driver model", closed-loop laws): pure-pursuit path
following with a first-order steering lag, as pure JAX (gradients pass through the driver).

The driver aims at the point of the path ``preview`` metres ahead (:mod:`._paths`). The
circle through the car's reference point, tangent to its heading and through that point
has curvature ``kappa = 2 l_y / L^2`` (``l_y`` the point's offset to the left of the
heading, ``L`` its distance); a car of wheelbase ``l`` follows it at low speed with the
road-wheel angle ``l kappa`` (kinematic steering), i.e. the steering-wheel command
``gain kappa`` with ``gain = ratio l`` (``ratio``: steering-wheel per road-wheel angle).
The driver's hands follow the command with the lag ``lag``: the steering-wheel angle is
the auxiliary state ``driver.steering`` (rad) with

    d(delta)/dt = (gain kappa(x, y, psi) - delta) / lag.

A state, not an algebraic law, because the rack's rate must not depend on the velocities
(:mod:`jaxveh.multibody._inputs`). The reference point is the chassis frame's origin
``(x, y)`` and the heading its yaw angle ``psi`` (coordinates of the chassis in both
forms, so the driver is the same function of the state in both). Pure pursuit has no
integral action: on a steady curve the car settles slightly off the path (more the more
it understeers); its steering there is the car's own steady-state steering for the path it
does follow.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._trig import sin_cos
from ..multibody import AbstractForceElement, StateInputs, zero_forces
from ..params import Range, checked_field
from ..vehicle import steering_rack, system_params, wheel_centres
from ..vehicle._corner_kinematics import corner_geometry, solve_pose
from ._driver import Manoeuvre
from ._paths import AbstractPath, Circle, DoubleLaneChange

#: The driver's auxiliary state.
DRIVER_STATES = ("driver.steering",)


class PurePursuit(eqx.Module):
    """Pure-pursuit driver (see the module docs): ``path``, ``preview`` distance (m),
    ``gain`` (rad of steering-wheel angle per 1/m of path curvature) and steering ``lag``
    (s)."""

    path: AbstractPath
    preview: Float[Array, ""] = checked_field("PurePursuit.preview", Range(0.5, 500.0, what="preview distance, m"))
    gain: Float[Array, ""] = checked_field("PurePursuit.gain", Range(0.0, 1e3, low_open=True,
                                                                     what="steering-wheel angle per curvature, rad m"))
    lag: Float[Array, ""] = checked_field("PurePursuit.lag", Range(1e-3, 5.0, what="steering lag, s"))

    def command(self, position: Float[Array, "2"], heading) -> Float[Array, ""]:
        """Steering-wheel angle (rad) the driver aims for at ``position`` (m), ``heading``
        (rad)."""
        rel = self.path.target(position, heading, self.preview) - position
        s, c = sin_cos(heading)
        ahead, left = c * rel[0] + s * rel[1], c * rel[1] - s * rel[0]
        return self.gain * 2.0 * left / (ahead * ahead + left * left)

    def rate(self, position, heading, angle) -> Float[Array, ""]:
        """Steering-wheel rate (rad/s) at the steering-wheel ``angle`` (rad)."""
        return (self.command(position, heading) - angle) / self.lag


def _pose(q, offset: int):
    return q[offset:offset + 2], q[offset + 3]


class DriverElement(AbstractForceElement):
    """The driver as a force element that applies nothing: it owns the state
    ``driver.steering``. ``pose``: the index of the chassis's x coordinate in ``q`` (x, y,
    z, yaw follow)."""

    driver: PurePursuit
    pose: int = eqx.field(static=True)
    aux_names: tuple[str, ...] = eqx.field(static=True, default=DRIVER_STATES)

    def __call__(self, kin, aux, system):
        out = zero_forces(kin, 1)
        position, heading = _pose(kin.q, self.pose)
        return eqx.tree_at(lambda f: f.aux_dot, out, self.driver.rate(position, heading, aux[0])[None])


def driver_inputs(car, driver: PurePursuit, pose: int, index: int, trim_rack) -> StateInputs:
    """The rack law of ``driver``: the trim rack plus :func:`jaxveh.vehicle.steering_rack`
    of the state ``aux[index]``; its rate from the driver's law at the chassis pose (``q``
    from index ``pose``)."""

    def value(t, q, aux):
        return trim_rack + steering_rack(car, aux[index])

    def rate(t, q, aux):
        position, heading = _pose(q, pose)
        return steering_rack(car, driver.rate(position, heading, aux[index]))

    return StateInputs(value, rate)


def steering_ratio(car) -> float:
    """Steering-wheel angle per mean front road-wheel angle (-) straight ahead at the
    design position: the exact sensitivity of the front uprights' toe to the rack (implicit
    function theorem on the link equations) times the rack ratio."""
    geometry = corner_geometry(car.system, system_params(car), wheel_centres(car.params.vehicle))

    def toe(rack):
        w = jax.vmap(solve_pose)(jnp.zeros((4, 5)), geometry, jnp.zeros(4), jnp.broadcast_to(rack, (4,)),
                                 geometry.inner)
        return 0.5 * (w[0, 2] + w[1, 2])

    zero = jnp.zeros(())
    toe_per_angle = jax.jvp(toe, (zero,), (steering_rack(car, jnp.ones(())),))[1]
    return float(1.0 / toe_per_angle)


def car_width(car) -> float:
    """The car's width (m): the wider axle's track plus its tyres' section width."""
    centres = np.asarray(wheel_centres(car.params.vehicle))
    return float(np.max(2.0 * np.abs(centres[:, 1]) + np.asarray(car.params.tyres.width)))


def pure_pursuit(car, path: AbstractPath, speed, preview_time: float = 0.8, lag: float = 0.1,
                 min_preview: float = 5.0) -> PurePursuit:
    """A :class:`PurePursuit` driver of ``car`` on ``path``: preview distance ``speed``
    (m/s) times ``preview_time`` (s), at least ``min_preview`` (m); gain from the car's
    :func:`steering_ratio` and wheelbase."""
    gain = steering_ratio(car) * float(car.params.vehicle.wheelbase)
    preview = jnp.maximum(jnp.asarray(speed, jnp.float64) * preview_time, min_preview)
    return PurePursuit(path=path, preview=preview, gain=gain, lag=lag)


def constant_radius(car, radius: float = 50.0, speed: float = 15.0, duration: float = 30.0, turn: float = 1.0,
                    preview_time: float = 0.8, lag: float = 0.1) -> Manoeuvre:
    """Closed-loop skid-pad: the car enters the circle of ``radius`` (m; ``turn`` 1 left, -1
    right) from straight running at ``speed`` (m/s, held) and follows it for ``duration``
    (s) with :func:`pure_pursuit`."""
    driver = pure_pursuit(car, Circle(radius=radius, turn=turn), speed, preview_time, lag)
    return Manoeuvre(steering=driver, speed=speed, duration=duration)


def lane_change(car, speed: float = 80.0 / 3.6, entry: float = 10.0, offset: float = 3.5,
                duration: float | None = None, preview_time: float = 0.8, lag: float = 0.1) -> Manoeuvre:
    """ISO 3888-1 double lane change at ``speed`` (m/s, held; the standard's 80 km/h by
    default), the track starting ``entry`` m ahead; ``duration`` (s) by default until the
    car is 10 m past the track's end."""
    path = DoubleLaneChange(entry=entry, offset=offset)
    duration = (float(path.end) + 10.0) / float(speed) if duration is None else duration
    driver = pure_pursuit(car, path, speed, preview_time, lag)
    return Manoeuvre(steering=driver, speed=speed, duration=duration)
