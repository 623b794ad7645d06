"""Shared plumbing for every jaxveh package: float64 mode, float fields, the parameter
error, the TOML reader, named range checks and the one gravity constant.

Importing :mod:`jaxveh` enables ``jax_enable_x64``: constraint tolerances (1e-9 m), Riccati
solutions and modal reductions need double precision. Library entry points call
:func:`check_x64`, which raises if a user switched it off afterwards.
"""

import contextlib
from importlib import resources
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import tomllib

jax.config.update("jax_enable_x64", True)

#: Standard gravity (m/s^2), used everywhere a default gravity is needed.
GRAVITY = 9.80665


class ParameterError(ValueError):
    """A vehicle data file or parameter value is missing, unknown or out of range."""


def check_x64() -> None:
    """Raise ``RuntimeError`` if JAX's 64-bit mode has been disabled."""
    if not jax.config.jax_enable_x64:
        raise RuntimeError(
            "jaxveh needs float64: jax_enable_x64 was switched off after importing "
            "jaxveh. Call jax.config.update('jax_enable_x64', True)."
        )


@contextlib.contextmanager
def run_time_checks_off():
    """Trace with every run-time check (``eqx.error_if``: jaxveh's traced parameter checks,
    Diffrax's and Optimistix's) compiled out.

    For compiled programs whose inputs the caller has checked before the call and whose
    failures it reads from returned flags. A run-time check puts a host callback into the
    program, and JAX's persistent compilation cache does not store programs with host
    callbacks: without them the car's programs (minutes to compile) compile once per
    machine instead of once per process. Equinox reads its ``EQX_ON_ERROR`` setting when a
    check is traced; this sets it to "off" meanwhile (no effect where Equinox lacks it).
    """
    import equinox._errors as errors

    if not hasattr(errors, "EQX_ON_ERROR"):
        yield
        return
    before = errors.EQX_ON_ERROR
    errors.EQX_ON_ERROR = "off"
    try:
        yield
    finally:
        errors.EQX_ON_ERROR = before


def run_time_checks_on() -> bool:
    """False inside :func:`run_time_checks_off`: a traced check would be compiled out, so
    jaxveh's checks skip building it (less to trace and compile)."""
    import equinox._errors as errors

    return getattr(errors, "EQX_ON_ERROR", "raise") != "off"


def as_float(x):
    """Convert to a float64 array (keeps tracers; a new value never retraces)."""
    return jnp.asarray(x, dtype=jnp.float64)


def float_field(**kwargs):
    """An Equinox field converted to a float64 array on construction."""
    return eqx.field(converter=as_float, **kwargs)


def is_concrete(x) -> bool:
    """True when ``x`` holds values (not a JAX tracer): checks can run in Python."""
    return not isinstance(x, jax.core.Tracer)


def check_range(name: str, value, *, low=None, high=None, low_open=False, high_open=False, what=""):
    """Validate every element of ``value`` against ``[low, high]`` (open ends on request).

    Concrete values raise :class:`ParameterError` naming ``name``, the offending value and
    the allowed range; traced values are checked at run time with ``eqx.error_if`` (the
    returned array must then be used), except inside :func:`run_time_checks_off`. NaN and
    infinities are always refused. Returns ``value`` as float64.
    """
    value = as_float(value)
    if not is_concrete(value) and not run_time_checks_on():
        return value
    lo_txt = "-inf" if low is None else f"{low:g}"
    hi_txt = "inf" if high is None else f"{high:g}"
    allowed = f"{'(' if low_open or low is None else '['}{lo_txt}, {hi_txt}{')' if high_open or high is None else ']'}"
    message = f"{name} must lie in {allowed}{' (' + what + ')' if what else ''}"
    if is_concrete(value):  # checked in NumPy: no eager JAX operation per check
        bad = _out_of_range(np, np.asarray(value), low, high, low_open, high_open)
        if bad.any():
            shown = np.asarray(value)[bad].ravel()[:3]
            raise ParameterError(f"{message}; got {', '.join(f'{v:g}' for v in shown)}")
        return value
    bad = _out_of_range(jnp, value, low, high, low_open, high_open)
    if is_concrete(bad):  # e.g. under an un-jitted jax.grad: the flag is known, the value traced
        if np.asarray(bad).any():
            raise ParameterError(message)
        return value
    return eqx.error_if(value, jnp.any(bad), message)


def _out_of_range(xp, value, low, high, low_open, high_open):
    """Elementwise: not finite or outside ``[low, high]`` (``xp`` is NumPy or jax.numpy)."""
    bad = ~xp.isfinite(value)
    if low is not None:
        bad = bad | ((value <= low) if low_open else (value < low))
    if high is not None:
        bad = bad | ((value >= high) if high_open else (value > high))
    return bad


def read_toml(path: str | Path | None, package: str, default: str, kind: str) -> tuple[dict, str]:
    """Parse a user TOML file, or the shipped ``package``/``default`` when ``path`` is None.

    Returns ``(table, where)`` with ``where`` naming the file for error messages. A missing
    file or invalid TOML raises :class:`ParameterError` naming the ``kind`` of file.
    """
    if path is None:
        text, where = resources.files(package).joinpath(default).read_text(), Path(default).name
    else:
        path = Path(path)
        if not path.is_file():
            raise ParameterError(f"{kind} file {str(path)!r} does not exist")
        text, where = path.read_text(), str(path)
    try:
        return tomllib.loads(text), where
    except tomllib.TOMLDecodeError as e:
        raise ParameterError(f"{where}: not valid TOML ({e})") from None
