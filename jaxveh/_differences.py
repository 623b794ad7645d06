"""A forward-difference Jacobian that compiles like one evaluation of the function, and
Newton's method with it.

``jax.jacfwd`` of the fast car's vector field is the field's forward-mode pass vectorised
over every state: XLA compiles it in about five times the field's own time (27 s of the
step-steer program's 53 s; docs/manoeuvre.md, "Compilation"). Where a Jacobian only needs
to be close (the IMEX split, whose two parts add up to the field whatever the matrix), a
forward difference taken column by column in a loop puts a single copy of the function
in the program. The loop is a ``lax.map``, not a ``vmap``: under an outer ``vmap`` its body
is batched over the outer batch alone, so the field's small LAPACK calls keep the batch
size they have in a plain run (docs/optimise.md: jaxlib's batched-LAPACK thread pool).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jax.flatten_util import ravel_pytree
from jaxtyping import Array, Float

from ._linalg import lu_factor, lu_solve

#: Relative step of the forward differences: about the square root of float64's epsilon,
#: where truncation and round-off errors balance.
RELATIVE_STEP = 1.5e-8


def _differences(fn, x, with_base: bool, columns=None):
    """``(values, h)``: ``fn`` (returning a pytree) at ``x`` plus each step ``h_j e_j`` (``j`` in
    ``columns``, static; default all), and at ``x`` itself as the last row when ``with_base``,
    in one ``lax.map``."""
    n = x.shape[0]
    h = (x + RELATIVE_STEP * jnp.maximum(jnp.abs(x), 1.0)) - x
    steps = jnp.diag(h)
    if columns is not None:
        steps, h = steps[np.asarray(columns, int)], h[np.asarray(columns, int)]
    if with_base:
        steps = jnp.concatenate([steps, jnp.zeros((1, n), x.dtype)])
    return jax.lax.map(lambda step: fn(x + step), steps), h


def _quotients(values, base, h):
    return ((values[: h.shape[0]] - base[None, :]) / h[:, None]).T


def forward_difference_jacobian(fn, x: Float[Array, " n"], fx=None, skip: tuple[int, ...] = ()
                                ) -> Float[Array, "m n"]:
    """``d fn / d x`` (m, n) at ``x`` (n,) by forward differences, steps
    ``RELATIVE_STEP * max(|x_j|, 1)`` (each rounded to one the floats represent). One
    evaluation per column, plus one at ``x`` unless its value ``fx`` is given, in a
    ``lax.map``: the program holds ``fn`` once. Relative error about 1e-8 where ``fn`` is
    smooth; across a kink the slope of the side the step goes to. The columns ``skip``
    (indices) are zero, not evaluated."""
    n = x.shape[0]
    if any(not 0 <= j < n for j in skip):
        raise ValueError(f"skip = {skip} must hold column indices in [0, {n})")
    columns = [j for j in range(n) if j not in set(skip)]
    values, h = _differences(fn, x, fx is None, columns if skip else None)
    quotients = _quotients(values, values[-1] if fx is None else fx, h)
    if not skip:
        return quotients
    return jnp.zeros((quotients.shape[0], n), quotients.dtype).at[:, np.asarray(columns, int)].set(quotients)


class _NewtonState(eqx.Module):
    step_size: Array  # the last step over atol + rtol |y|, largest component
    residual: Array  # the residual before the last step over atol, largest component
    steps: Array


class DifferenceNewton(optx.AbstractRootFinder):
    """Newton's method with a forward-difference Jacobian (a fresh one each step, the residual
    at the current point the difference loop's last row) and
    an LU solve that stays unbatched under ``vmap`` (:mod:`jaxveh._linalg`). It stops, as
    Optimistix's ``Newton`` does, when the last step is within ``atol + rtol |y|`` and the
    residual before it within ``atol``. The Jacobian's error (about 1e-8 of its entries)
    only slows the last step's convergence; derivatives of the root come from Optimistix's
    implicit function theorem on the exact residual, not from the iteration."""

    rtol: float
    atol: float
    norm: object = optx.max_norm

    def init(self, fn, y, args, options, f_struct, aux_struct, tags):
        inf = jnp.asarray(jnp.inf)
        return _NewtonState(inf, inf, jnp.asarray(0))

    def step(self, fn, y, args, options, state, tags):
        del options, tags
        flat, unravel = ravel_pytree(y)

        def flat_fn(x):
            fx, aux = fn(unravel(x), args)
            return ravel_pytree(fx)[0], aux

        # the residual at y is the loop's last row: the program holds the function once
        (values, auxes), h = _differences(flat_fn, flat, with_base=True)
        f_flat, aux = values[-1], jax.tree.map(lambda a: a[-1], auxes)
        step = lu_solve(lu_factor(_quotients(values, f_flat, h)), f_flat)
        new = flat - step
        size = jnp.max(jnp.abs(step) / (self.atol + self.rtol * jnp.abs(new)))
        return unravel(new), _NewtonState(size, jnp.max(jnp.abs(f_flat)) / self.atol, state.steps + 1), aux

    def terminate(self, fn, y, args, options, state, tags):
        del fn, y, args, options, tags
        converged = (state.step_size < 1.0) & (state.residual < 1.0)
        failed = ~jnp.isfinite(state.step_size) & (state.steps > 0)
        return converged | failed, optx.RESULTS.where(failed, optx.RESULTS.nonlinear_divergence,
                                                      optx.RESULTS.successful)

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        del fn, args, options, state, tags, result
        return y, aux, {}
