"""Reference paths for the closed-loop driver (:mod:`._pursuit`), in the ground plane (m):
the car starts at the origin heading along +x, y to its left.

- :class:`Circle`: the constant-radius skid-pad, entered tangentially at the origin.
- :class:`DoubleLaneChange`: the ISO 3888-1 double lane change. The standard fixes the
  track's sections (lengths 15, 30, 25, 25, 15, 15 m), the lane widths from the car's width
  ``b`` (1.1 b + 0.25, 1.2 b + 0.25, 1.3 b + 0.25 m) and a 3.5 m lateral offset; it marks
  the lanes with cones and prescribes no path. The reference path here (our choice, stated
  in docs/manoeuvre.md) is the lanes' centreline with the offset lane's centre 3.5 m to the
  left, joined over the two transition sections by quintic blends (continuous curvature).

Each path gives the preview point a distance ahead of the car (:meth:`target`) and the
signed lateral distance of points from the path (:meth:`lateral_error`), both pure JAX.
"""

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._core import ParameterError, is_concrete
from .._trig import arctan2, sin_cos
from ..params import Range, checked_field

#: ISO 3888-1 sections: (length m, lane-width factor on the car's width, lane-width
#: addition m, lane centre: 0 the start lane, 1 the offset lane; None: a transition).
ISO_3888_1_SECTIONS = ((15.0, 1.1, 0.25, 0), (30.0, None, None, None), (25.0, 1.2, 0.25, 1),
                       (25.0, None, None, None), (15.0, 1.3, 0.25, 0), (15.0, 1.3, 0.25, 0))


class AbstractPath(eqx.Module):
    """A path in the ground plane."""

    @abc.abstractmethod
    def target(self, position: Float[Array, "2"], heading, distance) -> Float[Array, "2"]:
        """The point of the path ``distance`` (m) ahead of a car at ``position`` (m)
        heading ``heading`` (rad)."""

    @abc.abstractmethod
    def lateral_error(self, position: Float[Array, "... 2"]) -> Float[Array, "..."]:
        """Signed distance (m) of points from the path, positive to the path's left."""


class Circle(AbstractPath):
    """Circle of ``radius`` (m) through the origin, tangent to +x there, turning left
    (``turn`` = 1) or right (-1); its centre is ``(0, turn radius)``."""

    radius: Float[Array, ""] = checked_field("Circle.radius", Range(1.0, 1e4, what="path radius, m"))
    turn: Float[Array, ""] = checked_field("Circle.turn", Range(-1.0, 1.0, what="turn direction (1 left, -1 right)"))

    def __check_init__(self):
        if is_concrete(self.turn) and abs(float(self.turn)) != 1.0:
            raise ParameterError(f"Circle.turn = {float(self.turn)!r} is out of range: allowed 1 (left) or -1 (right)")

    def _centre(self):
        return jnp.stack([jnp.zeros_like(self.radius), self.turn * self.radius])

    def target(self, position, heading, distance):
        del heading
        rel = position - self._centre()
        angle = arctan2(rel[1], rel[0]) + self.turn * distance / self.radius
        s, c = sin_cos(angle)
        return self._centre() + self.radius * jnp.stack([c, s])

    def lateral_error(self, position):
        # left of a left turn is inside the circle
        rel = position - jnp.broadcast_to(self._centre(), jnp.shape(position))
        return self.turn * (self.radius - jnp.linalg.norm(rel, axis=-1))


def _smootherstep(s):
    s = jnp.clip(s, 0.0, 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s))


class DoubleLaneChange(AbstractPath):
    """ISO 3888-1 double lane change (see the module docs) starting ``entry`` m ahead of the
    car's start, with the lane ``offset`` (m, positive to the left) between the lanes'
    centres."""

    entry: Float[Array, ""] = checked_field("DoubleLaneChange.entry", Range(0.0, 1e3, what="run-up, m"))
    offset: Float[Array, ""] = checked_field("DoubleLaneChange.offset",
                                             Range(-10.0, 10.0, what="lateral offset of the second lane, m"))

    def _starts(self):
        lengths = [s[0] for s in ISO_3888_1_SECTIONS]
        return [self.entry + sum(lengths[:k]) for k in range(len(lengths) + 1)]

    def centre(self, x):
        """The path's y (m) at ``x`` (m)."""
        x0 = self._starts()
        out = _smootherstep((x - x0[1]) / (x0[2] - x0[1])) - _smootherstep((x - x0[3]) / (x0[4] - x0[3]))
        return self.offset * out

    def target(self, position, heading, distance):
        del heading
        x = position[0] + distance
        return jnp.stack([x, self.centre(x)])

    def lateral_error(self, position):
        return position[..., 1] - self.centre(position[..., 0])

    def lanes(self, car_width) -> list[tuple[float, float, float, float]]:
        """The marked lanes ``(x_start, x_end, y_centre, width)`` (m) for a car ``car_width``
        (m) wide (concrete values)."""
        x0 = self._starts()
        out = []
        for k, (_, factor, extra, lane) in enumerate(ISO_3888_1_SECTIONS):
            if factor is not None:
                out.append((float(x0[k]), float(x0[k + 1]), float(lane * self.offset), factor * car_width + extra))
        return out

    @property
    def end(self):
        """x (m) where the track ends."""
        return self._starts()[-1]
