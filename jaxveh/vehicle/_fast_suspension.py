"""The push-rod suspensions of the fast car as one computation for all their corners.

The same forces as the library's :class:`~._suspension.PushrodSuspension` elements (the
chain of :mod:`._pushrod` per corner: wishbone point D, rocker angle in closed form, spring
length and their rates, the spring-damper law, the anti-roll bar, the rocker balance and
the wishbone's load sharing), with the corners of every element on one vectorised axis
instead of one computation per axle, and the forces gathered onto the points instead of
scattered.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._pushrod import RockerMount, WishboneGeometry
from ._springs import SpringDamperLaw
from ._suspension import PushrodSuspension, corner_forces, corner_state


class CornerSuspensions(eqx.Module):
    """The corners of several :class:`PushrodSuspension` elements on one leading axis (n):
    ``points`` (static, n x 6) their points' indices, ``wishbone``, ``mount``, ``law``
    stacked, ``arb_rate`` (n, N m/rad) the bar rate of each corner's axle (0 for a lone
    corner) and ``partner`` (static, n) the other corner on its bar (itself if none)."""

    points: tuple[tuple[int, ...], ...] = eqx.field(static=True)
    partner: tuple[int, ...] = eqx.field(static=True)
    wishbone: WishboneGeometry
    mount: RockerMount
    law: SpringDamperLaw
    arb_rate: Float[Array, " n"]


def _table_shapes(element: PushrodSuspension):
    return tuple(jnp.shape(x)[1:] for x in jax.tree.leaves(element.law))


def split_suspensions(elements) -> tuple[CornerSuspensions | None, tuple]:
    """``(suspensions, others)``: the push-rod suspensions among ``elements`` (those without
    auxiliary states) as one :class:`CornerSuspensions` and the other elements in their
    order; ``(None, elements)`` when there are none or their spring-damper tables differ in
    size (they cannot share one axis) or two corners load one point (the forces are
    gathered, not summed)."""
    picked = [e for e in elements if isinstance(e, PushrodSuspension) and not e.aux_names]
    points = [k for e in picked for row in e.points for k in row]
    if not picked or len({_table_shapes(e) for e in picked}) > 1 or len(set(points)) != len(points):
        return None, tuple(elements)
    return four_corner_suspension(picked), tuple(e for e in elements if not any(e is p for p in picked))


def four_corner_suspension(elements) -> CornerSuspensions:
    """The corners of push-rod suspension ``elements`` (spring-damper tables of one size) in
    one :class:`CornerSuspensions`."""

    def cat(*x):
        return jnp.concatenate([jnp.atleast_1d(v) for v in x])

    partner, arb, start = [], [], 0
    for e in elements:
        n = len(e.points)
        partner += [start + 1, start] if n == 2 else [start]
        arb.append(jnp.broadcast_to(e.arb_rate if n == 2 else jnp.zeros_like(e.arb_rate), (n,)))
        start += n
    return CornerSuspensions(
        points=sum((e.points for e in elements), ()),
        partner=tuple(partner),
        wishbone=jax.tree.map(cat, *(e.wishbone for e in elements)),
        mount=jax.tree.map(cat, *(e.mount for e in elements)),
        law=jax.tree.map(cat, *(e.law for e in elements)),
        arb_rate=jnp.concatenate(arb),
    )


def suspension_forces(s: CornerSuspensions, kin) -> Float[Array, "np 3"]:
    """Forces (N, global axes) of all the corners' push-rod paths on every point of
    ``kin`` (zero where none acts)."""
    idx = np.asarray(s.points, dtype=int)
    (lengths, thetas), (rates, _) = jax.vmap(corner_state)(kin.x[idx], kin.xd[idx], s.wishbone, s.mount)
    bar = -s.arb_rate * (thetas + thetas[np.asarray(s.partner)])
    spring = jax.vmap(lambda law, length, rate: law(length, rate))(s.law, lengths, rates)
    forces = jax.vmap(corner_forces)(kin.x[idx], s.wishbone, s.mount, thetas, spring, bar).reshape(-1, 3)
    slot = np.full(kin.x.shape[0], forces.shape[0])
    slot[idx.reshape(-1)] = np.arange(forces.shape[0])
    return jnp.concatenate([forces, jnp.zeros((1, 3), forces.dtype)])[slot]
