"""Range checks for the FE design path.

Concrete values raise :class:`~jaxveh._core.ParameterError` naming the field and its
allowed range; traced values (inside ``jit``, ``grad``, ``vmap``: an optimiser's design
variables) are checked at run time with ``eqx.error_if``, so the returned array must be
used in place of the argument. Every check refuses NaN.

These mirror :func:`jaxveh._core.check_range` (same messages) but test concrete values in
NumPy: inside a ``jit`` trace every ``jnp`` operation is staged, even on concrete
constants (a frame closed over by a jitted function), so a concrete value's range test
must not go through ``jnp``.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._core import ParameterError, as_float, is_concrete


def _interval(low, high, low_open, high_open) -> str:
    lo = "-inf" if low is None else f"{low:g}"
    hi = "inf" if high is None else f"{high:g}"
    return f"{'(' if low_open or low is None else '['}{lo}, {hi}{')' if high_open or high is None else ']'}"


def check_interval(name: str, value, *, low=None, high=None, low_open=False, high_open=False, what=""):
    """Every element of ``value`` in the interval ``[low, high]`` (open ends on request).

    Returns ``value`` as float64 (with a run-time check attached when traced).
    """
    message = f"{name} must lie in {_interval(low, high, low_open, high_open)}{' (' + what + ')' if what else ''}"

    def bad(xp, v):
        out = xp.isnan(v)
        if low is not None:
            out = out | ((v <= low) if low_open else (v < low))
        if high is not None:
            out = out | ((v >= high) if high_open else (v > high))
        return out

    if is_concrete(value):
        v = np.asarray(value, dtype=np.float64)
        b = bad(np, v)
        if b.any():
            raise ParameterError(f"{message}; got {', '.join(f'{x:g}' for x in v[b].ravel()[:3])}")
        return as_float(value)
    value = as_float(value)
    return eqx.error_if(value, jnp.any(bad(jnp, value)), message)


def check_positive(name: str, value, what: str = ""):
    """``value`` (every element) in ``(0, inf)``."""
    return check_interval(name, value, low=0.0, high=float("inf"), low_open=True, high_open=True, what=what)


def check_nonnegative(name: str, value, what: str = ""):
    """``value`` (every element) in ``[0, inf)``."""
    return check_interval(name, value, low=0.0, high=float("inf"), high_open=True, what=what)


def check_relation(value, bad_fn, message: str, **operands):
    """Return ``value``; refuse it when ``bad_fn(xp, **operands)`` is true anywhere.

    A relation between several fields (a wall thicker than half the diameter).
    ``bad_fn`` receives the array module (``numpy`` when every operand is concrete,
    ``jax.numpy`` otherwise). Concrete operands raise
    ``ParameterError(message + "; got name = value, ...")``; traced ones attach
    ``eqx.error_if(value, any(bad), message)``.
    """
    if all(is_concrete(v) for v in operands.values()):
        arrays = {k: np.asarray(v, dtype=np.float64) for k, v in operands.items()}
        if np.any(bad_fn(np, **arrays)):
            got = ", ".join(f"{k} = {_fmt(v)}" for k, v in arrays.items())
            raise ParameterError(f"{message}; got {got}")
        return value
    return eqx.error_if(value, jnp.any(bad_fn(jnp, **operands)), message)


def _fmt(a: np.ndarray) -> str:
    if a.ndim == 0:
        return f"{float(a):g}"
    return "[" + ", ".join(f"{x:g}" for x in a.ravel()[:6]) + (", ...]" if a.size > 6 else "]")
