"""Trigonometric functions as fused arithmetic (the car's vector field calls hundreds).

XLA's CPU backend evaluates ``sin``, ``cos``, ``tan``, ``atan2`` and ``acos`` element by
element through the C library, about 10 ns each (20 ns for ``acos``), where a product or a
quotient costs 0.5 ns and ``exp`` 1 ns: on this machine the fast car's field spent about
6 us of its 60-90 us in 618 such calls (docs/manoeuvre.md, "Speed", thirtieth
measurement). The functions here are the same functions written as range reductions,
polynomials and selects, which XLA fuses with their neighbours and vectorises:

- ``sin``, ``cos``, ``sin_cos``, ``tan``: reduction by the nearest multiple of pi / 2 with
  pi / 2 split in three parts (Cody and Waite; each part's product with the multiple exact
  for |x| < 2^26 pi / 2, about 1e8 rad), then the Taylor series of sin and cos on
  |r| <= pi / 4 to the 17th and 16th power (truncation below 1e-18 relative).
- ``arctan``, ``arctan2``, ``arcsin``, ``arccos``: the argument reduced to [0, 1] by the
  reciprocal, then taken about the nearest of the centres ``c = k / 8``,
  ``atan t = atan c + atan((t - c) / (1 + t c))``, whose remainder (at most 1 / 16) goes
  by the arctangent's series to the 15th power.

Each agrees with NumPy's to a few units in the last place (tests/test_trig.py) and
keeps the symmetries exactly (odd functions odd, even ones even). The derivatives are the
closed forms by ``jax.custom_jvp`` (for ``sin``, ``cos`` the other of the pair, which one
call computes together), so forward and reverse mode cost what ``jnp``'s do.
"""

from decimal import Decimal, localcontext
from math import factorial

import jax
import jax.numpy as jnp
import numpy as np

#: pi to 63 digits (the reduction's constants are exact splits of it)
_PI = "3.14159265358979323846264338327950288419716939937510582097494459"


def _half_pi_parts(parts: int, bits: int) -> tuple[float, ...]:
    """pi / 2 as ``parts`` doubles whose sum approximates it to about ``parts * bits`` bits,
    all but the last with at most ``bits`` significant bits (their products with integers
    below 2^(53 - bits) are exact)."""
    out = []
    with localcontext() as context:
        context.prec = 80
        rest = Decimal(_PI) / 2
        for k in range(parts):
            x = float(rest)
            if k < parts - 1:
                mantissa, exponent = np.frexp(x)
                x = float(np.ldexp(np.floor(mantissa * 2.0**bits), int(exponent) - bits))
            out.append(x)
            rest -= Decimal(x)
    return tuple(out)


_PIO2_PARTS = _half_pi_parts(3, 27)
_PIO2 = float(np.pi / 2)
_TWO_OVER_PI = float(2 / np.pi)
#: sin r = r (1 - r^2 / 3! + r^4 / 5! - ...) and cos r = 1 - r^2 / 2! + ... as polynomials in r^2
_SIN = tuple((-1.0) ** k / factorial(2 * k + 1) for k in range(9))
_COS = tuple((-1.0) ** k / factorial(2 * k) for k in range(9))
#: atan t = t (1 - t^2 / 3 + t^4 / 5 - ...) for |t| <= 1 / 16
_ATAN = tuple((-1.0) ** k / (2 * k + 1) for k in range(8))
#: the arctangent's centres k / 8 on [0, 1] and their arctangents
_ATAN_CENTRES = 8
_ATAN_TABLE = tuple(float(np.arctan(k / _ATAN_CENTRES)) for k in range(_ATAN_CENTRES + 1))


def _horner(coefficients, z):
    out = coefficients[-1]
    for c in coefficients[-2::-1]:
        out = out * z + c
    return out


def _float(x):
    """``x`` as a floating array (integers as float64)."""
    x = jnp.asarray(x)
    return x if jnp.issubdtype(x.dtype, jnp.floating) else x.astype(jnp.float64)


def _sin_cos(x):
    j = jnp.round(x * _TWO_OVER_PI)
    r = x
    for part in _PIO2_PARTS:
        r = r - j * part
    z = r * r
    s = r * _horner(_SIN, z)
    c = _horner(_COS, z)
    quadrant = j - 4.0 * jnp.floor(0.25 * j)  # 0, 1, 2, 3
    odd = (quadrant == 1.0) | (quadrant == 3.0)
    sin = jnp.where(odd, c, s)
    cos = jnp.where(odd, s, c)
    sin = jnp.where(quadrant >= 2.0, -sin, sin)
    cos = jnp.where((quadrant == 1.0) | (quadrant == 2.0), -cos, cos)
    return sin, cos


@jax.custom_jvp
def sin_cos(x):
    """``(sin x, cos x)`` of an array (rad) together, one reduction for both."""
    return _sin_cos(_float(x))


@sin_cos.defjvp
def _sin_cos_jvp(primals, tangents):
    (x,), (dx,) = primals, tangents
    s, c = sin_cos(x)
    return (s, c), (c * dx, -s * dx)


def sin(x):
    """``sin x`` (rad)."""
    return sin_cos(x)[0]


def cos(x):
    """``cos x`` (rad)."""
    return sin_cos(x)[1]


def tan(x):
    """``tan x`` (rad)."""
    s, c = sin_cos(x)
    return s / c


def _atan_unit(t):
    """``atan t`` for t in [0, 1]: ``atan c + atan((t - c) / (1 + t c))`` about the
    nearest centre ``c = k / 8``, whose remainder is at most 1 / 16."""
    k = jnp.round(t * _ATAN_CENTRES)
    c = k * (1.0 / _ATAN_CENTRES)
    d = (t - c) / (1.0 + t * c)
    base = jnp.zeros_like(t)
    for i, value in enumerate(_ATAN_TABLE[1:], start=1):
        base = jnp.where(k == i, value, base)
    return base + d * _horner(_ATAN, d * d)


def _atan(x):
    a = jnp.abs(x)
    large = a > 1.0
    base = _atan_unit(jnp.where(large, 1.0 / jnp.where(large, a, 1.0), a))
    return jnp.copysign(jnp.where(large, _PIO2 - base, base), x)


@jax.custom_jvp
def arctan(x):
    """``atan x`` (rad)."""
    return _atan(_float(x))


@arctan.defjvp
def _arctan_jvp(primals, tangents):
    (x,), (dx,) = primals, tangents
    return arctan(x), dx / (1.0 + x * x)


def _atan2(y, x):
    ax, ay = jnp.abs(x), jnp.abs(y)
    big, small = jnp.maximum(ax, ay), jnp.minimum(ax, ay)
    ratio = jnp.where(big > 0.0, small / jnp.where(big > 0.0, big, 1.0), 0.0)
    base = _atan_unit(ratio)
    base = jnp.where(ay > ax, _PIO2 - base, base)
    base = jnp.where(x < 0.0, 2.0 * _PIO2 - base, base)
    return jnp.copysign(base, y)


@jax.custom_jvp
def arctan2(y, x):
    """``atan2(y, x)`` (rad, in [-pi, pi]) of finite ``y``, ``x``."""
    return _atan2(_float(y), _float(x))


@arctan2.defjvp
def _arctan2_jvp(primals, tangents):
    (y, x), (dy, dx) = primals, tangents
    return arctan2(y, x), (x * dy - y * dx) / (x * x + y * y)


def _complement(x):
    return jnp.sqrt((1.0 - x) * (1.0 + x))


@jax.custom_jvp
def arcsin(x):
    """``asin x`` (rad) for x in [-1, 1]."""
    x = _float(x)
    return _atan2(x, _complement(x))


@arcsin.defjvp
def _arcsin_jvp(primals, tangents):
    (x,), (dx,) = primals, tangents
    return arcsin(x), dx / _complement(x)


@jax.custom_jvp
def arccos(x):
    """``acos x`` (rad) for x in [-1, 1]."""
    x = _float(x)
    return _atan2(_complement(x), x)


@arccos.defjvp
def _arccos_jvp(primals, tangents):
    (x,), (dx,) = primals, tangents
    return arccos(x), -dx / _complement(x)
