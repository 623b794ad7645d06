"""The push-rod suspension as a multibody force element (thesis section 6.1.5).

One element holds the push-rod spring-dampers of one or two corners (the two of an axle,
with the anti-roll bar between their rockers). From the global positions and velocities of
each corner's points A, B (lower wishbone pivots), C (its ball joint on the upright), P, Q
(rocker axis) and T (spring on the chassis) it evaluates the chain of :mod:`._pushrod`
(point D, rocker angle, spring length, their rates by ``jax.jvp``), the spring-damper force
``F_s = F(l_s, l_s_dot)`` of its :class:`~._springs.SpringDamperLaw` (N, positive in
compression; tables, bump stop), the bar moment
``M = -k_arb (θ_left + θ_right)`` on each rocker (the right side is the mirror image, so
heave turns the rockers by opposite angles about their mirrored axes and only roll twists
the bar), the rocker balance and the wishbone's load distribution, and applies the forces
at A, B, P, Q, T (chassis: points of the modal body load its modes) and C (upright).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import float_field
from ..multibody import AbstractForceElement, ElementForces, zero_forces
from ._pushrod import (
    RockerMount,
    WishboneGeometry,
    point_d,
    rocker_angle,
    rocker_geometry,
    rocker_loads,
    rocker_mount,
    rocker_on_chassis,
    spring_length,
    wishbone_geometry,
    wishbone_loads,
)
from ._springs import SpringDamperLaw

#: Points of one corner the element reads and loads, in this order.
CORNER_POINTS = ("A", "B", "C", "P", "Q", "T")


def _chain(x, wishbone: WishboneGeometry, mount: RockerMount):
    """``(l_s, θ)`` of one corner from its six point positions (rows as CORNER_POINTS)."""
    xa, xb, xc, xp, xq, xt = x
    rocker = rocker_on_chassis(mount, xp, xq, xt)
    theta = rocker_angle(rocker, point_d(xa, xb, xc, wishbone))
    return spring_length(rocker, xt, theta), theta


def corner_state(x, xd, wishbone: WishboneGeometry, mount: RockerMount):
    """``(l_s, θ), (l_s_dot, θ_dot)``: spring length (m) and rocker angle (rad) of one corner
    and their rates from the point velocities ``xd`` (m/s)."""
    return jax.jvp(lambda xx: _chain(xx, wishbone, mount), (x,), (xd,))


def corner_forces(x, wishbone: WishboneGeometry, mount: RockerMount, theta, spring_force, bar_moment):
    """Forces (N, rows as CORNER_POINTS) of one corner's push-rod path on its six points."""
    xa, xb, xc, xp, xq, xt = x
    rocker = rocker_on_chassis(mount, xp, xq, xt)
    xd = point_d(xa, xb, xc, wishbone)
    rl = rocker_loads(rocker, xd, xt, theta, spring_force, bar_moment)
    wl = wishbone_loads(xa, xb, xc, wishbone, rl.on_d)
    return jnp.stack([wl.on_a, wl.on_b, wl.on_c, rl.on_p, rl.on_q, rl.on_t])


class PushrodSuspension(AbstractForceElement):
    """Push-rod spring-dampers of one or two corners with an anti-roll bar (two corners:
    left then right). ``points`` (static): per corner the system's indices of
    :data:`CORNER_POINTS`; ``wishbone``, ``mount``, ``law``: per-corner geometry and
    spring-damper law stacked on a leading axis; ``arb_rate`` (N m/rad of bar twist, two
    corners only). Build with :func:`pushrod_suspension`."""

    points: tuple[tuple[int, ...], ...] = eqx.field(static=True)
    wishbone: WishboneGeometry
    mount: RockerMount
    law: SpringDamperLaw
    arb_rate: Float[Array, ""] = float_field(default=0.0)
    aux_names: tuple[str, ...] = eqx.field(static=True, default=())

    def states(self, kin):
        """``(l_s, θ), (l_s_dot, θ_dot)`` per corner (arrays of the corner count)."""
        idx = np.asarray(self.points, dtype=int)
        return jax.vmap(corner_state)(kin.x[idx], kin.xd[idx], self.wishbone, self.mount)

    def spring_forces(self, lengths, rates):
        """Spring-damper forces (N, positive in compression) per corner."""
        return jax.vmap(lambda law, length, rate: law(length, rate))(self.law, lengths, rates)

    def __call__(self, kin, aux, system):
        idx = np.asarray(self.points, dtype=int)
        (lengths, thetas), (rates, _) = self.states(kin)
        twist = jnp.sum(thetas) if len(self.points) == 2 else jnp.zeros_like(self.arb_rate)
        bar = jnp.broadcast_to(-self.arb_rate * twist, thetas.shape)
        forces = jax.vmap(corner_forces)(kin.x[idx], self.wishbone, self.mount, thetas,
                                         self.spring_forces(lengths, rates), bar)
        out = zero_forces(kin)
        return ElementForces(forces=out.forces.at[idx.reshape(-1)].add(forces.reshape(-1, 3)),
                             torques=out.torques, aux_dot=out.aux_dot)


def pushrod_suspension(system, corners, hard_points, law, arb_rate=0.0):
    """A :class:`PushrodSuspension` for ``corners`` (point-name prefixes in ``system``, e.g.
    ``("front_left.", "front_right.")`` or ``("",)`` for the quarter car) with their design
    hard points (one ``{name: xyz}`` per corner, m, any common frame: A, B, C, D, P, Q, R, S,
    T) and spring-damper ``law`` (one for all corners, or one per corner with tables of
    equal sizes)."""
    if not 1 <= len(corners) <= 2:
        raise ValueError(f"corners must name one corner or the two of an axle, got {len(corners)}")
    names = [[f"{c}{n}" for n in CORNER_POINTS] for c in corners]
    missing = [n for row in names for n in row if n not in system.point_names]
    if missing:
        raise ValueError(f"the system has no points {missing} (the push-rod path needs {CORNER_POINTS} per corner)")
    wishbones, mounts = [], []
    for hp in hard_points:
        xa, xb, xc, xd = (jnp.asarray(hp[n], jnp.float64) for n in "ABCD")
        wishbones.append(wishbone_geometry(xa, xb, xc, xd))
        rocker = rocker_geometry(*(jnp.asarray(hp[n], jnp.float64) for n in "PQRS"), xd)
        mounts.append(rocker_mount(rocker, jnp.asarray(hp["T"], jnp.float64)))

    def stack(items):
        return jax.tree.map(lambda *x: jnp.stack(x), *items)

    laws = [law] * len(corners) if isinstance(law, SpringDamperLaw) else list(law)
    if len(laws) != len(corners):
        raise ValueError(f"law: give one law or one per corner ({len(corners)}), got {len(laws)}")
    if len({tuple(jnp.shape(a) for a in jax.tree.leaves(x)) for x in laws}) != 1:
        raise ValueError("law: the corners' tables must have the same sizes to share one element")
    return PushrodSuspension(
        points=tuple(tuple(system.point_index(p) for p in row) for row in names),
        wishbone=stack(wishbones),
        mount=stack(mounts),
        law=stack(laws),
        arb_rate=arb_rate,
    )
