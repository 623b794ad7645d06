"""Input checks of the public analytic API (see "Input validation" in ``docs/analytic.md``).

The implementation modules do not re-check the vehicle on every internal call (the 4-DOF
right-hand side would repeat ~40 comparisons per evaluation). Instead the public names of
:mod:`jaxveh.analytic` are these wrappers: they check the vehicle (or axle tyre) once with
:func:`jaxveh.params.check_analytic_vehicle` and, where the function takes one, that the
``speed`` is positive, then call the implementation. Entry points that take other inputs
(speeds, ay, times, λ, µ, frequencies) check those themselves.
"""

import functools
import inspect

from ..params import POSITIVE, Range, check, check_analytic_vehicle, check_axle_tyre

#: Forward speed u (m/s): the 4-DOF model divides by it (slip angles, eq. 3.28).
SPEED = Range(0.0, low_open=True, what="forward speed u, m/s; the 4-DOF model divides by it")
#: Lateral acceleration of a skid-pad steady state (m/s^2): u = sqrt(ay R) must be positive.
LATERAL_ACCELERATION = Range(0.0, low_open=True, what="lateral acceleration ay, m/s^2; u = sqrt(ay R)")
#: λ = kF/(kF + kR): 0 and 1 (all roll stiffness on one axle) are the edges of the design maps.
LAM = Range(0.0, 1.0, what="roll stiffness proportion kF/(kF + kR)")
#: µ = kC/(kF + kR): a chassis needs some torsional stiffness.
MU = Range(0.0, low_open=True, what="normalised chassis torsional stiffness kC/(kF + kR)")


def check_speed(speed, name: str = "speed"):
    """``speed`` (m/s) checked > 0; returns it as float64 (use the result)."""
    return check(name, speed, SPEED)


def _wrap(fn, check_first):
    signature = inspect.signature(fn)
    takes_speed = "speed" in signature.parameters

    @functools.wraps(fn)
    def checked(first, *args, **kwargs):
        first = check_first(first)
        if takes_speed:
            bound = signature.bind(first, *args, **kwargs)
            bound.arguments["speed"] = check_speed(bound.arguments["speed"])
            return fn(*bound.args, **bound.kwargs)
        return fn(first, *args, **kwargs)

    return checked


def vehicle_checked(fn):
    """``fn(vehicle, ...)`` with the vehicle (and a ``speed`` argument) checked first."""
    return _wrap(fn, check_analytic_vehicle)


def tyre_checked(fn):
    """``fn(tyre, ...)`` with the :class:`~jaxveh.params.AxleTyre` checked first."""
    return _wrap(fn, check_axle_tyre)


__all__ = ["LAM", "LATERAL_ACCELERATION", "MU", "POSITIVE", "SPEED", "check_speed", "tyre_checked", "vehicle_checked"]
