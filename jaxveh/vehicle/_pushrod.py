"""Push-rod suspension force path (thesis section 6.1.5, eqs. 6.4-6.12).

All positions are in one frame (the chassis frame, m) and all functions are pure and
differentiable. The chain, as a chassis engineer follows it:

1. **Lower wishbone** (Fig. 6.4): a massless triangle A-B-C with the push-rod point D fixed
   on it. Its frame has ``x`` along A->B, ``y`` in the plane ABC towards C, ``z = x × y``
   (eqs. 6.4-6.7, written with vectors instead of the yaw-pitch-roll angles). G is the foot
   of C on the A-B axis. :func:`wishbone_geometry` stores D in that frame at the design
   position; :func:`point_d` puts it back for any A, B, C (eq. 6.8).
2. **Rocker** (Fig. 6.5): turns about the axis P-Q; the push rod of length ``l_p`` joins
   D to R. R moves on a circle about the axis, so ``|D - R(θ)| = l_p`` (eq. 6.9) is
   ``α cos θ + β sin θ = γ``, solved in closed form (:func:`rocker_angle`) instead of by the
   thesis's Newton iteration; the branch is the one through the design position (θ = 0).
3. **Spring-damper** between the rocker point S and the chassis point T: length and rate
   (eq. 6.10; the force law is the caller's: linear, table, bump stop).
4. **Rocker moment balance** about P-Q gives the push-rod force (:func:`rocker_loads`),
   with the reactions at P and Q on the chassis.
5. **Wishbone** (eqs. 6.11-6.12, :func:`wishbone_loads`): the push-rod force at D is shared
   between C (upright) and A, B (chassis) with the thesis's beam model: G-C a beam clamped
   in its plane at G and pinned at C, hinged about the A-B axis; A and B share G's load by
   the lever rule and carry its moments as couples.
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._trig import sin_cos

Vec = Float[Array, "3"]


def _unit(v):
    return v / jnp.linalg.norm(v)


# ---------------------------------------------------------------------------------------
# lower wishbone (eqs. 6.4-6.8)
# ---------------------------------------------------------------------------------------
def wishbone_frame(xa: Vec, xb: Vec, xc: Vec) -> tuple[Float[Array, "3 3"], Vec]:
    """``(W, x_G)``: the wishbone axes as columns of ``W`` (x along A->B, y towards C in
    the plane ABC, z = x × y) and G, the foot of C on the A-B axis (m)."""
    ex = _unit(xb - xa)
    xg = xa + jnp.dot(xc - xa, ex) * ex
    ey = _unit(xc - xg)
    return jnp.stack([ex, ey, jnp.cross(ex, ey)], axis=1), xg


class WishboneGeometry(eqx.Module):
    """Fig. 6.4 parameters of one lower wishbone (m): ``m`` = A->G, ``n`` = G->B (along
    A->B, signed),
    ``length`` = |G C| (the thesis's ``l = a + b``), and D in the wishbone frame relative to G:
    ``d`` (along A->B), ``a`` (along G->C; ``b = l - a``), ``e`` (out of the plane)."""

    m: Float[Array, ""]
    n: Float[Array, ""]
    length: Float[Array, ""]
    d: Float[Array, ""]
    a: Float[Array, ""]
    e: Float[Array, ""]

    @property
    def b(self):
        return self.length - self.a

    @property
    def d_local(self) -> Vec:
        return jnp.stack([self.d, self.a, self.e])


def wishbone_geometry(xa: Vec, xb: Vec, xc: Vec, xd: Vec) -> WishboneGeometry:
    """The wishbone's parameters from its four points at the design position (m)."""
    w, xg = wishbone_frame(xa, xb, xc)
    local = w.T @ (xd - xg)
    m = jnp.dot(xg - xa, w[:, 0])  # signed: G may lie beyond A or B
    return WishboneGeometry(m=m, n=jnp.linalg.norm(xb - xa) - m, length=jnp.linalg.norm(xc - xg), d=local[0],
                            a=local[1], e=local[2])


def point_d(xa: Vec, xb: Vec, xc: Vec, geometry: WishboneGeometry) -> Vec:
    """Eq. (6.8): the push-rod point D for the current A, B, C (m)."""
    w, xg = wishbone_frame(xa, xb, xc)
    return xg + w @ geometry.d_local


# ---------------------------------------------------------------------------------------
# rocker and push rod (eq. 6.9)
# ---------------------------------------------------------------------------------------
def rotate_about_axis(x: Vec, xp: Vec, xq: Vec, angle) -> Vec:
    """``x`` turned by ``angle`` (rad, right-handed about P->Q) about the axis through P, Q."""
    u = _unit(xq - xp)
    r = x - xp
    s, c = sin_cos(angle)
    return xp + r * c + jnp.cross(u, r) * s + u * jnp.dot(u, r) * (1.0 - c)


class RockerGeometry(eqx.Module):
    """A rocker turning about P-Q (chassis points) with the push-rod end R and the spring
    end S at the design position, the push-rod length ``l_p`` and the branch of eq. (6.9)
    through the design position (``branch`` = ±1; m)."""

    xp: Vec
    xq: Vec
    xr: Vec
    xs: Vec
    l_p: Float[Array, ""]
    branch: Float[Array, ""]


def _circle(rocker: RockerGeometry, xd: Vec):
    """``(α, β, γ)`` of ``α cos θ + β sin θ = γ`` (eq. 6.9 on R's circle about the axis)."""
    u = _unit(rocker.xq - rocker.xp)
    centre = rocker.xp + jnp.dot(rocker.xr - rocker.xp, u) * u
    radius_vec = rocker.xr - centre
    radius = jnp.linalg.norm(radius_vec)
    e1 = radius_vec / radius
    e2 = jnp.cross(u, e1)
    to_d = xd - centre
    gamma = (jnp.dot(to_d, to_d) + radius**2 - rocker.l_p**2) / (2.0 * radius)
    return jnp.dot(to_d, e1), jnp.dot(to_d, e2), gamma


def rocker_geometry(xp: Vec, xq: Vec, xr: Vec, xs: Vec, xd: Vec) -> RockerGeometry:
    """The rocker at the design position, with the push rod joining D to R."""
    probe = RockerGeometry(xp, xq, xr, xs, jnp.linalg.norm(xd - xr), jnp.asarray(1.0))
    alpha, beta, _ = _circle(probe, xd)
    branch = jnp.where(jnp.arctan2(beta, alpha) > 0.0, -1.0, 1.0)
    return eqx.tree_at(lambda r: r.branch, probe, branch)


def rocker_reach(rocker: RockerGeometry, xd: Vec) -> Float[Array, ""]:
    """``|γ| / sqrt(α² + β²)``: below 1 the push rod reaches the rocker circle; above 1
    D is too far from (or too close to) the rocker for the rod's length."""
    alpha, beta, gamma = _circle(rocker, xd)
    return jnp.abs(gamma) / jnp.sqrt(alpha**2 + beta**2)


def rocker_angle(rocker: RockerGeometry, xd: Vec) -> Float[Array, ""]:
    """Eq. (6.9) in closed form: the rocker rotation (rad, about P->Q) that puts R at the
    push-rod length from D, on the branch through the design position (0 there). Where the
    rod cannot reach (:func:`rocker_reach` > 1) the angle is that of the closest approach."""
    alpha, beta, gamma = _circle(rocker, xd)
    rho = jnp.sqrt(alpha**2 + beta**2)
    return jnp.arctan2(beta, alpha) + rocker.branch * jnp.arccos(jnp.clip(gamma / rho, -1.0, 1.0))


def spring_length(rocker: RockerGeometry, xt: Vec, angle) -> Float[Array, ""]:
    """Length |S - T| (m) of the spring-damper unit at the rocker angle (rad)."""
    xs = rotate_about_axis(rocker.xs, rocker.xp, rocker.xq, angle)
    return jnp.linalg.norm(xs - xt)


class RockerLoads(eqx.Module):
    """Loads of one rocker (N, chassis frame): ``pushrod`` (rod force, positive in
    compression), ``on_d`` (force of the rod on the wishbone at D), ``on_p``, ``on_q``,
    ``on_t`` (forces on the chassis at P, Q and the spring's chassis end T)."""

    pushrod: Float[Array, ""]
    on_d: Vec
    on_p: Vec
    on_q: Vec
    on_t: Vec


def rocker_loads(rocker: RockerGeometry, xd: Vec, xt: Vec, angle, spring_force, axial_moment=0.0) -> RockerLoads:
    """Moment balance of the massless rocker about P-Q.

    ``spring_force`` (N, positive in compression: the unit pushes S away from T);
    ``axial_moment`` (N m, about P->Q): any further moment on the rocker, e.g. an anti-roll
    bar's. The push rod carries what balances both about the axis; P and Q carry the rest
    (the axial force shared equally: statically indeterminate, a documented choice)."""
    xs = rotate_about_axis(rocker.xs, rocker.xp, rocker.xq, angle)
    xr = rotate_about_axis(rocker.xr, rocker.xp, rocker.xq, angle)
    u = _unit(rocker.xq - rocker.xp)
    f_s = spring_force * _unit(xs - xt)  # on the rocker at S
    rod = _unit(xr - xd)  # compression pushes R away from D
    moment_s = jnp.dot(jnp.cross(xs - rocker.xp, f_s), u) + axial_moment
    pushrod = -moment_s / jnp.dot(jnp.cross(xr - rocker.xp, rod), u)
    f_r = pushrod * rod  # on the rocker at R
    total = f_s + f_r
    moment_p = jnp.cross(xs - rocker.xp, f_s) + jnp.cross(xr - rocker.xp, f_r)
    axis = rocker.xq - rocker.xp
    moment_perp = moment_p - jnp.dot(moment_p, u) * u
    on_q_perp = jnp.cross(moment_perp, axis) / jnp.dot(axis, axis)
    on_q = on_q_perp + 0.5 * jnp.dot(total, u) * u
    return RockerLoads(pushrod=pushrod, on_d=-f_r, on_p=total - on_q, on_q=on_q, on_t=-f_s)


# ---------------------------------------------------------------------------------------
# wishbone load distribution (eqs. 6.11-6.12)
# ---------------------------------------------------------------------------------------
class WishboneLoads(eqx.Module):
    """Forces (N, chassis frame) that a load at D puts on the chassis at A and B and on the
    upright at C; they sum to the load and carry its moment."""

    on_a: Vec
    on_b: Vec
    on_c: Vec


def beam_loads(geometry: WishboneGeometry, f_local: Vec) -> tuple[Vec, Vec, Float[Array, ""], Float[Array, ""]]:
    """Eq. (6.11), derived anew: ``(at G, at C, torsion M_y at G, in-plane M_z at G)`` in
    wishbone axes for a force ``f_local`` at D (wishbone axes). G-C is a uniform beam along
    y, clamped in its plane (x deflection, moment about z) and in torsion at G, pinned at C,
    hinged about x at G (the wishbone turns about A-B) so the z loads are shared as on a
    simply supported beam. D sits ``(d, a, e)`` from G; its offset adds the moments
    ``(-e f_y, e f_x - d f_z, d f_y)`` at the beam point ``a``."""
    g = geometry
    span, a, b = g.length, g.a, g.b
    fx, fy, fz = f_local[0], f_local[1], f_local[2]
    mx, my, mz = -g.e * fy, g.e * fx - g.d * fz, g.d * fy
    # axial: both ends held, shared by the segments' stiffness
    cy = a / span * fy
    # out of plane: simply supported, moment about x at G balances
    cz = (a * fz + mx) / span
    # in plane: propped cantilever; tip compatibility of a cantilever under fx and mz at a
    cx = a**2 * (3.0 * span - a) / (2.0 * span**3) * fx - 3.0 * (span**2 - b**2) / (2.0 * span**3) * mz
    at_c = jnp.stack([cx, cy, cz])
    at_g = f_local - at_c
    moment_z = -a * fx + mz + span * cx  # moment about z carried by the clamp at G
    return at_g, at_c, my, moment_z


def wishbone_loads(xa: Vec, xb: Vec, xc: Vec, geometry: WishboneGeometry, force_d: Vec) -> WishboneLoads:
    """Eqs. (6.11)-(6.12): a force at D (N, chassis frame) shared between A, B (chassis)
    and C (upright). G's force goes to A and B by the lever rule (A: n/p, B: m/p), its
    moments about y and z as couples of z and y forces over |A B| = p."""
    w, _ = wishbone_frame(xa, xb, xc)
    at_g, at_c, my, mz = beam_loads(geometry, w.T @ force_d)
    p = geometry.m + geometry.n
    couple = jnp.stack([jnp.zeros_like(mz), -mz / p, my / p])
    on_a = geometry.n / p * at_g + couple
    on_b = geometry.m / p * at_g - couple
    return WishboneLoads(on_a=w @ on_a, on_b=w @ on_b, on_c=w @ at_c)


# ---------------------------------------------------------------------------------------
# the rocker carried by the chassis
# ---------------------------------------------------------------------------------------
class RockerMount(eqx.Module):
    """The rocker's R and S at design, in axes fixed by three chassis points: P (origin),
    the axis u = P->Q and the direction of T perpendicular to it (``e``, ``u × e``, ``u``;
    m), with the push-rod length and branch of :class:`RockerGeometry`. Rebuilt from the
    current P, Q, T by :func:`rocker_on_chassis`, the rocker follows the chassis (and its
    deformation at the mounts) with no reference to the chassis's orientation, so its angle
    is a function of point positions only and its rate their ``jvp``."""

    r_local: Vec
    s_local: Vec
    l_p: Float[Array, ""]
    branch: Float[Array, ""]


def _mount_axes(xp: Vec, xq: Vec, xt: Vec) -> Float[Array, "3 3"]:
    u = _unit(xq - xp)
    to_t = xt - xp
    e = _unit(to_t - jnp.dot(to_t, u) * u)
    return jnp.stack([e, jnp.cross(u, e), u], axis=1)


def rocker_mount(rocker: RockerGeometry, xt: Vec) -> RockerMount:
    """The mount of a rocker at design, with the spring's chassis end T."""
    axes = _mount_axes(rocker.xp, rocker.xq, xt)
    return RockerMount(axes.T @ (rocker.xr - rocker.xp), axes.T @ (rocker.xs - rocker.xp), rocker.l_p, rocker.branch)


def rocker_on_chassis(mount: RockerMount, xp: Vec, xq: Vec, xt: Vec) -> RockerGeometry:
    """The rocker (at its design angle) for the current chassis points P, Q, T."""
    axes = _mount_axes(xp, xq, xt)
    return RockerGeometry(xp, xq, xp + axes @ mount.r_local, xp + axes @ mount.s_local, mount.l_p, mount.branch)
