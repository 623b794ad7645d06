"""Named design variables, bounded reparametrisation, and an Optax augmented-Lagrangian solver.

A design variable is a leaf of the parameter pytree named by its attribute path
(``"kC"``, ``"tyre.scale_rear"``) or, when the problem supplies ``apply``, any label the
``apply`` function understands (``"lam"`` for the roll stiffness proportion). Each variable
lives in ``[lower, upper]`` through a logistic map of an unconstrained variable (in log space
with ``log=True``), so every Optax step stays feasible for the bounds.

Constraints are scalar functions ``g(params) <= 0`` and equalities ``h(params) = 0``,
handled by the Powell-Hestenes-Rockafellar augmented Lagrangian: outer multiplier updates
around ``inner_steps`` Optax steps.
"""

import math
from collections.abc import Callable
from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax

from jaxveh import ParameterError
from jaxveh.params import get_at, set_all


class Variable(NamedTuple):
    """A bounded design variable: ``name`` (leaf path or label), bounds, optional log scale."""

    name: str
    lower: float
    upper: float
    log: bool = False


def get_leaf(params, path: str):
    """Value of ``params`` at ``path`` (dotted fields, optional indices: ``"kC"``,
    ``"arb_rates[0]"``; :func:`jaxveh.params.get_at`); ``ParameterError`` (a ``ValueError``)
    if it does not exist or is a derived property rather than a stored field."""
    return get_at(params, path)


def set_leaves(params, values: dict):
    """Copy of ``params`` with the values at the paths of ``values`` replaced
    (:func:`jaxveh.params.set_all`)."""
    return set_all(params, values)


def target(fn: Callable, value: float, scale: float = 1.0) -> Callable:
    """Objective ``((fn(params) - value)/scale)^2`` that drives ``fn`` to ``value``."""
    return lambda params: ((fn(params) - value) / scale) ** 2


class Problem(eqx.Module):
    """``minimise objective(params)`` subject to ``constraint(params) <= 0`` for each constraint
    and ``equality(params) = 0`` for each equality.

    Attributes:
        params: base parameter pytree (e.g. an ``AnalyticVehicle``).
        variables: the design variables.
        objective: scalar function of the parameter pytree.
        constraints: scalar functions of the parameter pytree, feasible when <= 0.
        equalities: scalar functions of the parameter pytree, feasible when 0.
        apply: ``apply(params, {name: value}) -> params``; default :func:`set_leaves`.
    """

    params: object
    variables: tuple[Variable, ...] = eqx.field(static=True)
    objective: Callable = eqx.field(static=True)
    constraints: tuple[Callable, ...] = eqx.field(static=True, default=())
    apply: Optional[Callable] = eqx.field(static=True, default=None)
    equalities: tuple[Callable, ...] = eqx.field(static=True, default=())

    def __check_init__(self):
        if not self.variables:
            raise ParameterError("Problem needs at least one design variable")
        names = [var.name for var in self.variables]
        if len(set(names)) != len(names):
            raise ParameterError(f"design variable names must be unique, got {names}")
        for var in self.variables:
            if not (math.isfinite(var.lower) and math.isfinite(var.upper)):
                raise ParameterError(f"variable {var.name!r}: bounds must be finite, got [{var.lower}, {var.upper}]")
            if not var.lower < var.upper:
                raise ParameterError(f"variable {var.name!r}: need lower < upper, got [{var.lower}, {var.upper}]")
            if var.log and var.lower <= 0.0:
                raise ParameterError(f"variable {var.name!r}: log scale needs lower > 0, got {var.lower}")
            if self.apply is None:
                get_leaf(self.params, var.name)

    def to_values(self, z) -> dict:
        """Unconstrained vector ``z`` -> ``{name: value}`` inside the bounds."""
        out = {}
        for i, var in enumerate(self.variables):
            s = jax.nn.sigmoid(z[i])
            if var.log:
                out[var.name] = jnp.exp(jnp.log(var.lower) + s * (jnp.log(var.upper) - jnp.log(var.lower)))
            else:
                out[var.name] = var.lower + s * (var.upper - var.lower)
        return out

    def to_z(self, values: dict):
        """Inverse of :meth:`to_values` (values must lie strictly inside the bounds)."""
        missing = [var.name for var in self.variables if var.name not in values]
        if missing:
            raise ParameterError(f"initial values missing for design variable(s) {missing}")
        zs = []
        for var in self.variables:
            x = float(values[var.name])
            if not var.lower < x < var.upper:
                raise ParameterError(f"initial {var.name} = {x} must lie strictly inside ({var.lower}, {var.upper})")
            if var.log:
                s = (np.log(x) - np.log(var.lower)) / (np.log(var.upper) - np.log(var.lower))
            else:
                s = (x - var.lower) / (var.upper - var.lower)
            zs.append(np.log(s / (1.0 - s)))
        return jnp.asarray(zs)

    def build(self, z):
        """Parameter pytree at unconstrained design ``z``."""
        apply = self.apply if self.apply is not None else set_leaves
        return apply(self.params, self.to_values(z))


class Result(NamedTuple):
    """Solution: variable values, parameter pytree, objective, constraint and equality
    values, history."""

    values: dict
    params: object
    objective: float
    constraints: list
    history: list
    equalities: list = []


def _lagrangian(problem: Problem, z, multipliers, rho):
    """The PHR augmented Lagrangian; ``multipliers``: the constraints' then the equalities'."""
    params = problem.build(z)
    value = problem.objective(params)
    n_con = len(problem.constraints)
    for k, g in enumerate(problem.constraints):
        c = g(params)
        value = value + (jnp.maximum(0.0, multipliers[k] + rho * c) ** 2 - multipliers[k] ** 2) / (2.0 * rho)
    for k, h in enumerate(problem.equalities, start=n_con):
        e = h(params)
        value = value + multipliers[k] * e + 0.5 * rho * e**2
    return value


def _check_settings(*, inner_steps, outer_steps, rho, rho_growth, constraint_tol) -> None:
    for name, value in (("inner_steps", inner_steps), ("outer_steps", outer_steps)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ParameterError(f"{name} must be a Python int >= 1; got {value!r}")
    for name, value, ok, allowed in (
        ("rho", rho, lambda x: x > 0.0, "(0, inf)"),
        ("rho_growth", rho_growth, lambda x: x >= 1.0, "[1, inf)"),
        ("constraint_tol", constraint_tol, lambda x: x > 0.0, "(0, inf)"),
    ):
        if not (math.isfinite(float(value)) and ok(float(value))):
            raise ParameterError(f"{name} must lie in {allowed}; got {value!r}")


def solve(
    problem: Problem,
    initial: dict,
    optimiser: optax.GradientTransformation | None = None,
    inner_steps: int = 300,
    outer_steps: int = 10,
    rho: float = 10.0,
    rho_growth: float = 4.0,
    constraint_tol: float = 1e-6,
) -> Result:
    """Minimise ``problem`` from ``initial`` values with Optax (default Adam, lr 0.05).

    Each outer iteration runs ``inner_steps`` optimiser steps on the augmented Lagrangian
    (one compiled ``lax.scan``), then updates multipliers and grows the penalty while the
    worst constraint violation (or an equality's size) exceeds ``constraint_tol``. Raises ``RuntimeError`` if the
    objective or gradient becomes non-finite. Settings are checked (``ParameterError``):
    ``inner_steps``, ``outer_steps`` >= 1, ``rho`` > 0, ``rho_growth`` >= 1,
    ``constraint_tol`` > 0. Parameter values out of their physical range during the solve
    raise the library's own runtime error (e.g. a vehicle field's allowed range).
    """
    _check_settings(inner_steps=inner_steps, outer_steps=outer_steps, rho=rho, rho_growth=rho_growth,
                    constraint_tol=constraint_tol)
    optimiser = optax.adam(0.05) if optimiser is None else optimiser
    z = problem.to_z(initial)
    n_con, n_eq = len(problem.constraints), len(problem.equalities)
    multipliers = jnp.zeros(n_con + n_eq)

    @eqx.filter_jit
    def inner(z, multipliers, rho):
        grad_fn = jax.value_and_grad(lambda zz: _lagrangian(problem, zz, multipliers, rho))

        def step(carry, _):
            z, state = carry
            value, grad = grad_fn(z)
            # Optax mixes int32 step counts with floats; allow it even under strict promotion.
            with jax.numpy_dtype_promotion("standard"):
                updates, state = optimiser.update(grad, state, z)
            return (optax.apply_updates(z, updates), state), value

        with jax.numpy_dtype_promotion("standard"):
            state = optimiser.init(z)
        (z, _), values = jax.lax.scan(step, (z, state), None, length=inner_steps)
        return z, values

    @eqx.filter_jit
    def evaluate(z):
        params = problem.build(z)
        fns = problem.constraints + problem.equalities
        return problem.objective(params), jnp.stack([g(params) for g in fns]) if fns else jnp.zeros(0)

    def infeasibility(cons):
        return float(jnp.max(jnp.concatenate([jnp.maximum(cons[:n_con], 0.0), jnp.abs(cons[n_con:])]), initial=0.0))

    history = []
    rho = jnp.asarray(rho, dtype=jnp.float64)
    for _ in range(outer_steps):
        z, values = inner(z, multipliers, rho)
        if not bool(jnp.all(jnp.isfinite(values))) or not bool(jnp.all(jnp.isfinite(z))):
            raise RuntimeError("optimisation produced a non-finite objective or design; check bounds and the objective")
        obj, cons = evaluate(z)
        values = {k: float(v) for k, v in problem.to_values(z).items()}
        history.append({"objective": float(obj), "max_violation": infeasibility(cons), **values})
        if n_con + n_eq == 0:
            break
        updated = multipliers + rho * cons
        multipliers = jnp.concatenate([jnp.maximum(0.0, updated[:n_con]), updated[n_con:]])
        if infeasibility(cons) > constraint_tol:
            rho = rho * rho_growth
        elif len(history) > 1 and abs(history[-1]["objective"] - history[-2]["objective"]) <= 1e-9 * max(
            1.0, abs(history[-1]["objective"])
        ):
            break
    obj, cons = evaluate(z)
    values = {k: float(v) for k, v in problem.to_values(z).items()}
    return Result(
        values=values,
        params=problem.build(z),
        objective=float(obj),
        constraints=[float(c) for c in cons[:n_con]],
        history=history,
        equalities=[float(c) for c in cons[n_con:]],
    )
