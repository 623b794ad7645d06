"""Named range checks for the public Python API (the data-file loaders have their own).

A :class:`Range` says which values a number may take. Two ways to apply one:

- :func:`checked_field`: an Equinox field that converts to float64 and checks the value on
  construction with :func:`jaxveh._core.check_range` (concrete values raise
  :class:`ParameterError` naming the field and the allowed range; traced values get an
  ``eqx.error_if`` stored in the field, so the check runs wherever the field is used).
- :func:`check_module`: checks every listed field of an existing module, plus relations
  between fields, and returns the module. Functions call it on their inputs, so values set
  with ``eqx.tree_at`` (which bypasses ``__init__``) or passed in traced by an optimiser are
  checked too. Concrete values are checked in NumPy and raise at once; all traced checks of
  one module share a single ``eqx.branched_error_if`` (one runtime branch, not one per field).
"""

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._core import ParameterError, as_float, check_range, is_concrete, run_time_checks_on
from ._schema import UNIT_TO_SI, Quantity


@dataclass(frozen=True)
class Range:
    """Allowed values ``[low, high]`` (``None``: unbounded; ``*_open``: bound excluded).

    ``what`` describes the quantity (and its unit) in error messages. NaN and infinities are
    never allowed (as in :func:`jaxveh._core.check_range`).
    """

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    what: str = ""

    def kwargs(self) -> dict:
        return dict(low=self.low, high=self.high, low_open=self.low_open, high_open=self.high_open, what=self.what)

    def allowed(self) -> str:
        """The interval as text, as :func:`jaxveh._core.check_range` writes it."""
        lo = "-inf" if self.low is None else f"{self.low:g}"
        hi = "inf" if self.high is None else f"{self.high:g}"
        left = "(" if self.low_open or self.low is None else "["
        right = ")" if self.high_open or self.high is None else "]"
        return f"{left}{lo}, {hi}{right}"

    def message(self, name: str) -> str:
        """The error message of :func:`jaxveh._core.check_range` for a traced value."""
        return f"{name} must lie in {self.allowed()}{' (' + self.what + ')' if self.what else ''}"

    def bad(self, x, xp=jnp):
        """Elementwise: ``x`` is NaN, infinite or outside the range (``xp``: ``np`` or ``jnp``)."""
        out = ~xp.isfinite(x)
        if self.low is not None:
            out = out | ((x <= self.low) if self.low_open else (x < self.low))
        if self.high is not None:
            out = out | ((x >= self.high) if self.high_open else (x > self.high))
        return out


_SI_UNIT = {"mm": "m", "deg": "rad", "Nm/deg": "Nm/rad", "Nms/deg": "Nms/rad", "km/h": "m/s", "1/deg": "1/rad"}


def quantity_range(q: Quantity) -> Range:
    """The allowed range of a data-file quantity, converted to SI units."""
    factor = UNIT_TO_SI[q.unit]
    unit = _SI_UNIT.get(q.unit, q.unit)
    what = q.description if unit == "-" else f"{q.description}, {unit}"
    low = None if q.lower is None else q.lower * factor
    high = None if q.upper is None else q.upper * factor
    return Range(low, high, q.lower_open, q.upper_open, what)


POSITIVE = Range(0.0, low_open=True)
NON_NEGATIVE = Range(0.0)


def _raise_if_bad(name: str, value, rng: Range) -> None:
    """Raise :class:`ParameterError` (check_range's message) if concrete ``value`` is bad."""
    arr = np.asarray(value, dtype=np.float64)
    bad = rng.bad(arr, np)
    if np.any(bad):
        shown = arr[bad].ravel()[:3]
        raise ParameterError(f"{rng.message(name)}; got {', '.join(f'{v:g}' for v in shown)}")


def check(name: str, value, rng: Range):
    """``check_range(name, value, **rng)`` as float64, and the value to use afterwards.

    Concrete values (Python numbers, NumPy or JAX arrays, also while tracing) are checked at
    once in NumPy. Traced values whose check is nonetheless known (eager ``jax.grad``, whose
    tracers carry concrete primals) raise :class:`ParameterError` too; values traced under
    ``jit``/``vmap`` are checked at run time by ``check_range``'s ``eqx.error_if``.
    """
    if is_concrete(value):
        _raise_if_bad(name, value, rng)
        if isinstance(value, jax.Array) and value.dtype == jnp.float64:
            return value
        return as_float(value)
    value = as_float(value)
    bad = jnp.any(rng.bad(value))
    if is_concrete(bad):
        if bool(bad):
            raise ParameterError(rng.message(name))
        return value
    return check_range(name, value, **rng.kwargs())


def check_static(name: str, value, rng: Range) -> float:
    """A static Python number (a setting, not a traced parameter) checked; returned as float."""
    _raise_if_bad(name, value, rng)
    return float(value)


def require(x, bad, message: str):
    """``x`` unchanged if ``bad`` is all false. A concrete true ``bad`` raises
    :class:`ParameterError` (``message``); a traced one is checked at run time with
    ``eqx.error_if`` (use the returned ``x``)."""
    if is_concrete(bad):
        if np.any(np.asarray(bad)):
            raise ParameterError(message)
        return x
    if not run_time_checks_on():
        return x
    return eqx.error_if(x, jnp.any(bad), message)


def check_int(name: str, value, low: int, what: str = "") -> int:
    """A static Python ``int`` >= ``low`` (sizes, orders, step counts); ``ParameterError`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        extra = f" ({what})" if what else ""
        raise ParameterError(f"{name} must be a Python int >= {low}{extra}; got {value!r}")
    return int(value)


def checked_field(name: str, rng: Range, **kwargs):
    """An Equinox field converted to float64 and checked against ``rng`` on construction."""
    return eqx.field(converter=lambda x: check(name, x, rng), **kwargs)


def array_module(x):
    """``numpy`` for NumPy arrays, else ``jax.numpy`` (relations run on either)."""
    return np if isinstance(x, np.ndarray) else jnp


#: A relation between fields: (name, function of the module giving a value, allowed range).
Relation = tuple[str, Callable, Range]


def check_module(module, prefix: str, ranges: Mapping[str, Range], relations: Sequence[Relation] = ()):
    """Check fields ``ranges`` (by attribute name) and ``relations`` of ``module``; return it.

    Concrete violations raise :class:`ParameterError` naming ``prefix.field``; traced values
    are checked at run time with one ``eqx.branched_error_if`` on the module's leaves, whose
    message names the first violated field (inside :func:`jaxveh._core.run_time_checks_off`
    traced values are not checked: the caller checked them before tracing). The returned module must be used. Relation
    functions receive NumPy leaves when the whole module is concrete (use ``array_module``).
    """
    original = module
    if all(is_concrete(x) for x in jax.tree.leaves(module)):
        # NumPy view: properties and relations evaluate without JAX dispatch.
        module = jax.tree.map(np.asarray, module)
        for key, rng in ranges.items():
            _raise_if_bad(f"{prefix}.{key}", getattr(module, key), rng)
        for name, fn, rng in relations:  # only once every field is valid
            _raise_if_bad(f"{prefix}: {name}", fn(module), rng)
        return original
    checks_on = run_time_checks_on()  # off: a traced check would be compiled out, so none is built
    names, preds = [], []
    items = [(f"{prefix}.{key}", getattr(module, key), rng) for key, rng in ranges.items()]
    if checks_on:
        items += [(f"{prefix}: {name}", fn(module), rng) for name, fn, rng in relations]
    for name, value, rng in items:
        if is_concrete(value):
            check(name, value, rng)
            continue
        if not checks_on:
            continue
        pred = jnp.any(rng.bad(value))
        if is_concrete(pred):  # eager jax.grad: the values are known
            if bool(pred):
                raise ParameterError(rng.message(name))
            continue
        names.append(rng.message(name))
        preds.append(pred)
    if not preds:
        return module
    bad = jnp.stack(preds)
    leaves, treedef = jax.tree.flatten(module)
    leaves = eqx.branched_error_if(leaves, jnp.any(bad), jnp.argmax(bad), names)
    return jax.tree.unflatten(treedef, leaves)
