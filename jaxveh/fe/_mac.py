"""Mode-set comparison: Modal Assurance Criterion and normalised frequency difference."""

import jax.numpy as jnp
from jaxtyping import Array, Float


def mac(
    phi_a: Float[Array, "n a"], phi_b: Float[Array, "n b"], M: Float[Array, "n n"] | None = None
) -> Float[Array, "a b"]:
    """Modal Assurance Criterion between two mode sets (columns).

    ``MAC_ij = (φa_iᵀ W φb_j)² / ((φa_iᵀ W φa_i)(φb_jᵀ W φb_j))`` with ``W = M`` (the
    mass-weighted form the thesis uses for Fig. 6.9b) or the identity if ``M`` is None.
    0: uncorrelated, 1: the same shape.
    """
    wb = phi_b if M is None else M @ phi_b
    wa = phi_a if M is None else M @ phi_a
    cross = phi_a.T @ wb
    na = jnp.sum(phi_a * wa, axis=0)
    nb = jnp.sum(phi_b * wb, axis=0)
    return cross**2 / (na[:, None] * nb[None, :])


def nrfd(f_reference: Float[Array, " n"], f_other: Float[Array, " n"]) -> Float[Array, " n"]:
    """Normalised relative frequency difference ``|f_other − f_ref| / f_ref`` (Fig. 6.9a)."""
    return jnp.abs(f_other - f_reference) / f_reference
