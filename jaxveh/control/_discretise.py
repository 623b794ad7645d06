"""Zero-order-hold discretisation of a continuous-time linear system (eq. 3.38)."""

import jax.numpy as jnp
import jax.scipy.linalg as jsl
from jaxtyping import Array, Float

from ..params import check
from ._butterworth import SAMPLE_TIME


def zoh(
    a_c: Float[Array, "n n"], b_c: Float[Array, "n m"], dt: Float[Array, ""] | float
) -> tuple[Float[Array, "n n"], Float[Array, "n m"]]:
    """Discretise ``x' = a_c x + b_c u`` with a zero-order hold on ``u`` over ``dt`` seconds.

    Uses the matrix exponential of the augmented matrix (Van Loan):
    ``expm([[a_c, b_c], [0, 0]] dt) = [[a_d, b_d], [0, I]]``, so ``a_d = exp(a_c dt)`` and
    ``b_d = int_0^dt exp(a_c s) ds b_c`` exactly, also when ``a_c`` is singular (the
    integrators ``Y`` and ``psi`` of the vehicle model). Differentiable in all arguments.

    **Arguments:** ``a_c`` (n, n) in 1/s, ``b_c`` (n, m) in state units per input unit per
    second, ``dt`` the sample time in s.

    **Returns:** ``(a_d, b_d)`` of ``x[k+1] = a_d x[k] + b_d u[k]``.
    """
    a_c = jnp.asarray(a_c)
    b_c = jnp.asarray(b_c)
    if a_c.ndim != 2 or a_c.shape[0] != a_c.shape[1]:
        raise ValueError(f"zoh: a_c must be square (n, n), got shape {a_c.shape}.")
    if b_c.ndim != 2 or b_c.shape[0] != a_c.shape[0]:
        raise ValueError(
            f"zoh: b_c must have shape (n, m) with n = {a_c.shape[0]}, got {b_c.shape}."
        )
    n, m = b_c.shape
    dt = check("zoh: dt", dt, SAMPLE_TIME)
    top = jnp.concatenate([a_c, b_c], axis=1)
    augmented = jnp.concatenate([top, jnp.zeros((m, n + m), dtype=a_c.dtype)], axis=0)
    phi = jsl.expm(augmented * dt)
    return phi[:n, :n], phi[:n, n:]
