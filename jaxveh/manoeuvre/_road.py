"""Road input: the four-post rig (thesis section 7.4.2, Fig. 7.9). Each wheel rolls on a
flat post whose height follows a constant-amplitude sine sweep; the posts move in phase
(heave) or with the two wheels of each axle in anti-phase and the diagonals together
(warp: the thesis's "lags of 180 deg ... while diagonal symmetry is maintained").

The car runs straight at the manoeuvre's speed with the steering held (a rolling-road
rig: the tyres need a rolling speed); the posts are the road under the wheels, so the
tyres see the post's height and its rate (their vertical damping acts on the rate).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import ParameterError
from .._trig import sin
from ..params import Range, checked_field
from ..vehicle import AbstractRoad
from ._driver import Manoeuvre, Straight, sweep_phase

#: Post phase of each corner (FL, FR, RL, RR) by pattern.
POST_PATTERNS = {"heave": (1.0, 1.0, 1.0, 1.0), "warp": (1.0, -1.0, -1.0, 1.0)}


def _check_phases(x):
    if np.shape(x) != (4,):
        raise ParameterError(f"PostSweep.phases has shape {np.shape(x)}: allowed 4 values (FL, FR, RL, RR)")
    return jnp.asarray(x, jnp.float64)


class PostSweep(AbstractRoad):
    """Four posts following ``phases[wheel] * amplitude * sin(phase(t))`` (m): a sine sweep
    from ``start`` (s), its frequency rising linearly from ``f0`` to ``f1`` (Hz) over
    ``sweep`` seconds, then holding ``f1``. ``phases``: +1 or -1 per corner (FL, FR, RL,
    RR; :data:`POST_PATTERNS`). Zero before ``start``, so the car starts on a flat road."""

    amplitude: Float[Array, ""] = checked_field("PostSweep.amplitude",
                                                Range(-0.1, 0.1, what="post displacement amplitude, m"))
    f0: Float[Array, ""] = checked_field("PostSweep.f0", Range(0.0, 200.0, what="start frequency, Hz"))
    f1: Float[Array, ""] = checked_field("PostSweep.f1", Range(0.0, 200.0, what="end frequency, Hz"))
    sweep: Float[Array, ""] = checked_field("PostSweep.sweep", Range(0.0, low_open=True, what="sweep time, s"))
    start: Float[Array, ""] = checked_field("PostSweep.start", Range(0.0, what="time, s"))
    phases: Float[Array, "4"] = eqx.field(converter=_check_phases)

    def displacement(self, t) -> Float[Array, ""]:
        """The post motion of a corner with phase +1 (m) at time ``t`` (s)."""
        return self.amplitude * sin(sweep_phase(t, self.f0, self.f1, self.sweep, self.start))

    def height(self, x, y, t, wheel):
        return self.phases[wheel] * self.displacement(t) + jnp.zeros_like(x + y)

    def kinks(self):
        """Start and end of the sweep (s): derivative jumps of the post motion."""
        return (self.start, self.start + self.sweep)


def four_post(speed: float = 50.0 / 3.6, pattern: str = "warp", amplitude: float = 0.002, f0: float = 0.0,
              f1: float = 30.0, sweep: float = 40.0, start: float = 0.5) -> Manoeuvre:
    """Four-post sine sweep (Fig. 7.9): the car rolling straight at ``speed`` (m/s) over
    posts moving by ``amplitude`` (m) in the ``pattern`` "heave" or "warp", the frequency
    rising from ``f0`` to ``f1`` (Hz) over ``sweep`` seconds after ``start`` (s); the run
    ends with the sweep."""
    if pattern not in POST_PATTERNS:
        allowed = ", ".join(map(repr, POST_PATTERNS))
        raise ParameterError(f"pattern = {pattern!r} is not a post pattern: allowed {allowed}")
    road = PostSweep(amplitude=amplitude, f0=f0, f1=f1, sweep=sweep, start=start, phases=POST_PATTERNS[pattern])
    return Manoeuvre(steering=Straight(), speed=speed, duration=start + sweep, road=road)
