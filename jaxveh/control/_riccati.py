"""Discrete algebraic Riccati equation (eq. 3.45), solved in JAX and differentiable.

Forward solve: the structure-preserving doubling algorithm (SDA) of Chu, Fan and Lin
(Linear Algebra Appl. 396, 2005). With ``A0 = a``, ``G0 = b r^-1 b^T``, ``H0 = q``::

    W = I + G H
    A <- A W^-1 A,   G <- G + A W^-1 G A^T,   H <- H + A^T H W^-1 A

``H`` converges quadratically to the stabilising solution ``P`` whenever ``(a, b)`` is
stabilisable and ``(a, q)`` detectable; eigenvalues of ``a`` on the unit circle (the
integrators of a vehicle's lateral position and heading) are allowed. Each step costs a
few dense ``n x n`` products; the 213-state preview plant converges in ~10 steps.

Gradients: implicit function theorem, not differentiation through the iterations. At the
optimum, ``P = Acl^T P Acl + k^T r k + q`` with ``Acl = a - b k`` and ``k`` stationary
(envelope theorem), so a perturbation satisfies the Stein (discrete Lyapunov) equation::

    dP - Acl^T dP Acl = dAcl^T P Acl + Acl^T P dAcl + k^T dr k + dq,   dAcl = da - db k

solved as ``dP = sum_j (Acl^T)^j S Acl^j`` by Smith doubling with a fixed number of
squarings (linear in ``S``, so JAX transposes it for reverse mode). Both ``jax.jvp`` /
``jax.jacfwd`` and ``jax.grad`` work, and ``jax.vmap`` over any argument.
"""

import functools

import equinox as eqx
import jax
import jax.lax as lax
import jax.numpy as jnp
from jaxtyping import Array, Float, Int

from ..params import POSITIVE, check_int, check_static, require


class RESULTS(eqx.Enumeration):
    """Outcome of :func:`solve_dare`; each failure carries its message."""

    successful = ""
    max_steps_reached = (
        "solve_dare: the doubling iteration did not converge within max_steps. Check that "
        "(a, b) is stabilisable and (a, q) detectable, or increase max_steps."
    )
    nonfinite = (
        "solve_dare: non-finite values (NaN/inf) in the Riccati solution; check the "
        "inputs for NaN/inf and that r is positive definite."
    )
    not_stabilising = (
        "solve_dare: the solution does not stabilise the closed loop (spectral radius of "
        "a - b k >= 1): (a, b) is not stabilisable or (a, q) not detectable."
    )


class DareSolution(eqx.Module):
    """Solution of ``P = a^T P a - a^T P b (r + b^T P b)^-1 b^T P a + q``.

    - ``p`` (n, n): stabilising symmetric solution (differentiable).
    - ``k`` (m, n): optimal gain ``(r + b^T P b)^-1 b^T P a``, control ``u = -k x``
      (differentiable).
    - ``residual``: ``||Riccati(P) - P||_F / ||P||_F`` (diagnostic, no gradient).
    - ``spectral_radius``: of ``a - b k`` (diagnostic, no gradient).
    - ``steps``: doubling steps taken.
    - ``result``: a :class:`RESULTS` item.
    """

    p: Float[Array, "n n"]
    k: Float[Array, "m n"]
    residual: Float[Array, ""]
    spectral_radius: Float[Array, ""]
    steps: Int[Array, ""]
    result: RESULTS


def _sym(x):
    return 0.5 * (x + x.T)


def _sda(a, b, q, r, rtol, max_steps):
    """Structure-preserving doubling; returns ``(P, steps, converged)``."""
    n = a.shape[0]
    eye = jnp.eye(n, dtype=a.dtype)
    g0 = _sym(b @ jnp.linalg.solve(r, b.T))

    def cond(state):
        step, _, _, _, change = state
        return (step < max_steps) & (change > rtol)  # NaN stops the loop too

    def body(state):
        step, a_k, g_k, h_k, _ = state
        w = eye + g_k @ h_k
        x = jnp.linalg.solve(w, jnp.concatenate([a_k, g_k], axis=1))
        wa, wg = x[:, :n], x[:, n:]
        h_next = _sym(h_k + a_k.T @ h_k @ wa)
        g_next = _sym(g_k + a_k @ wg @ a_k.T)
        a_next = a_k @ wa
        change = jnp.linalg.norm(h_next - h_k) / jnp.maximum(
            jnp.linalg.norm(h_next), jnp.finfo(a.dtype).tiny
        )
        return step + 1, a_next, g_next, h_next, change

    init = (jnp.asarray(0), a, g0, q, jnp.asarray(jnp.inf, dtype=a.dtype))
    steps, _, _, p, change = lax.while_loop(cond, body, init)
    return p, steps, change <= rtol


def riccati_gain(a, b, r, p):
    """Optimal gain ``k = (r + b^T p b)^-1 b^T p a`` of the discrete LQR, ``u = -k x``."""
    return jnp.linalg.solve(r + b.T @ p @ b, b.T @ p @ a)


def riccati_residual(a, b, q, r, p):
    """``a^T p a - a^T p b (r + b^T p b)^-1 b^T p a + q - p`` (zero at a solution)."""
    k = riccati_gain(a, b, r, p)
    return a.T @ p @ a - (a.T @ p @ b) @ k + q - p


def _stein_doubling(acl, s, doublings):
    """``sum_{j < 2^doublings} (acl^T)^j s acl^j``: Smith doubling, linear in ``s``."""

    def square(power, _):
        return power @ power, power

    _, powers = lax.scan(square, acl, None, length=doublings)

    def accumulate(x, power):
        return x + power.T @ x @ power, None

    x, _ = lax.scan(accumulate, s, powers)
    return x


@functools.partial(jax.custom_jvp, nondiff_argnums=(0,))
def _attach_implicit_gradient(doublings, p, a, b, q, r):
    """Identity on the converged ``p``; its JVP is the implicit-function tangent."""
    del doublings, a, b, q, r
    return p


@_attach_implicit_gradient.defjvp
def _attach_jvp(doublings, primals, tangents):
    p, a, b, q, r = primals
    _, da, db, dq, dr = tangents
    k = riccati_gain(a, b, r, p)
    acl = a - b @ k
    dacl = da - db @ k
    pa = p @ acl
    s = dacl.T @ pa + pa.T @ dacl + k.T @ dr @ k + dq
    return p, _sym(_stein_doubling(acl, _sym(s), doublings))



@eqx.filter_jit
def solve_dare(
    a: Float[Array, "n n"],
    b: Float[Array, "n m"],
    q: Float[Array, "n n"],
    r: Float[Array, "m m"],
    *,
    rtol: float = 1e-12,
    max_steps: int = 100,
    stein_doublings: int = 32,
    throw: bool = True,
) -> DareSolution:
    """Solve the discrete algebraic Riccati equation of the LQR ``min sum x^T q x + u^T r u``.

    ``x[k+1] = a x[k] + b u[k]``; ``q`` positive semi-definite, ``r`` positive definite
    (both are symmetrised). Differentiable in ``a, b, q, r`` (implicit function theorem;
    see the module docstring), forward and reverse mode, and vmappable. An ``r`` that is not
    positive definite raises ``ParameterError`` (``eqx.error_if`` when traced).

    **Arguments:**

    - ``rtol``: stop when the relative Frobenius change of the iterate is below this.
    - ``max_steps``: static cap on doubling steps (each step squares the horizon).
    - ``stein_doublings``: static number of squarings in the gradient's Stein sum; it sums
      ``2**stein_doublings`` terms, exact for closed-loop spectral radius ``rho`` while
      ``rho ** 2**stein_doublings`` is negligible.
    - ``throw``: raise a runtime error (``eqx.error_if``) carrying the
      :class:`RESULTS` message if the solve failed; with ``throw=False`` inspect
      ``solution.result`` instead.
    """
    a, b, q, r = (jnp.asarray(x) for x in (a, b, q, r))
    n = a.shape[0]
    if a.shape != (n, n) or b.ndim != 2 or b.shape[0] != n:
        raise ValueError(f"solve_dare: need a (n, n) and b (n, m); got {a.shape}, {b.shape}.")
    m = b.shape[1]
    if q.shape != (n, n) or r.shape != (m, m):
        raise ValueError(
            f"solve_dare: need q ({n}, {n}) and r ({m}, {m}); got {q.shape}, {r.shape}."
        )
    rtol = check_static("solve_dare: rtol", rtol, POSITIVE)
    max_steps = check_int("solve_dare: max_steps", max_steps, 1)
    stein_doublings = check_int("solve_dare: stein_doublings", stein_doublings, 1)
    q, r = _sym(q), _sym(r)
    r = require(r, ~(jnp.linalg.eigvalsh(r)[0] > 0.0), "solve_dare: r must be positive definite (eigenvalues > 0)")
    constants = tuple(lax.stop_gradient(x) for x in (a, b, q, r))
    p_star, steps, converged = _sda(*constants, rtol, max_steps)
    residual = jnp.linalg.norm(riccati_residual(*constants, p_star)) / jnp.maximum(
        jnp.linalg.norm(p_star), jnp.finfo(p_star.dtype).tiny
    )
    acl = constants[0] - constants[1] @ riccati_gain(constants[0], constants[1], constants[3], p_star)
    radius = jnp.max(jnp.abs(jnp.linalg.eigvals(acl)))
    finite = jnp.all(jnp.isfinite(p_star)) & jnp.isfinite(residual)
    result = RESULTS.where(
        ~finite,
        RESULTS.nonfinite,
        RESULTS.where(
            ~converged,
            RESULTS.max_steps_reached,
            RESULTS.where(radius >= 1.0, RESULTS.not_stabilising, RESULTS.successful),
        ),
    )
    p = _attach_implicit_gradient(stein_doublings, p_star, a, b, q, r)
    if throw:
        p = result.error_if(p, result != RESULTS.successful)
    return DareSolution(
        p=p,
        k=riccati_gain(a, b, r, p),
        residual=residual,
        spectral_radius=radius,
        steps=steps,
        result=result,
    )
