"""Corner kinematics of the fast car: the upright pose relative to the chassis frame as a
function of the suspension travel, the rack travel and the chassis deformation at the five
inner link pivots, for the four corners at once.

Each corner's upright (six coordinates) is held by five links (Table 6.3); with the travel
given, its other five pose coordinates ``w = [dx, dy, toe, camber, spin]`` (the wheel
centre's move from its design position in the chassis frame, and ``"zxy"`` angles as the
library's uprights) solve the five link equations
``(|d|^2 - l^2) / (2 l) = 0``. The solve is exact: Newton from a guess, a fixed number of
iterations vectorised over the corners. Its derivatives come from the implicit function
theorem (a custom JVP), not from differentiating the iterations, so velocities and the
velocity-product terms are exact at the solved pose and any order of autodiff works.

The guess comes from a :class:`KinematicMap`: tensor-product Chebyshev fits of ``w`` over
travel x rack on the undeformed chassis, built from the current design by a vmapped grid of
exact solves (so gradients with respect to hard points flow through the map too, though the
solved pose does not depend on the guess). With the map the guess is within a few
micrometres of the solution for chassis deformations of a millimetre, and two Newton
iterations reach round-off; :func:`pose_residual` reports what is left.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._trig import arccos, cos, sin_cos
from ..multibody import System, SystemParams
from ._car import CORNERS
from ._corner import QUARTER_CAR_LINKS

#: Inner (chassis) and outer (upright) points of the five links, in Table 6.3's order.
INNER_POINTS = tuple(link[1] for link in QUARTER_CAR_LINKS)
OUTER_POINTS = tuple(link[2] for link in QUARTER_CAR_LINKS)
#: Newton iterations from the map's guess (static).
POSE_ITERATIONS = 2
#: Range of the kinematic map: suspension travel (m) and rack travel (m). Outside it the
#: guess is extrapolated and the solve may need more iterations (see :func:`pose_residual`).
MAP_TRAVEL = (-0.05, 0.05)
MAP_RACK = (-0.025, 0.025)
#: Chebyshev degree of the map in travel and in rack.
MAP_DEGREE = (10, 8)
#: Newton iterations of the grid solves that build the map (continuation from the design).
MAP_ITERATIONS = 12


class CornerGeometry(eqx.Module):
    """Link geometry of the four corners (leading axis: FL, FR, RL, RR; SI units, chassis
    and upright frames). ``inner`` (4, 5, 3) pivots on the undeformed chassis, ``inner_shapes``
    (4, 5, 3, n) their translational mode shapes times the coupling factor, ``rack`` (4, 5)
    1 where the rack moves the pivot along the chassis y axis, ``outer`` (4, 5, 3) the
    upright points from the wheel centre, ``lengths`` (4, 5) link lengths, ``centre`` (4, 3)
    the design wheel centres in the chassis frame."""

    inner: Float[Array, "4 5 3"]
    inner_shapes: Float[Array, "4 5 3 nm"]
    rack: Float[Array, "4 5"]
    outer: Float[Array, "4 5 3"]
    lengths: Float[Array, "4 5"]
    centre: Float[Array, "4 3"]


def corner_geometry(system: System, params: SystemParams, centres) -> CornerGeometry:
    """The link geometry of the car's library parameters and design wheel centres (4, 3)
    (JAX operations: differentiable)."""
    inner, shapes, rack, outer, lengths = [], [], [], [], []
    chassis = system.body_names.index("chassis")
    n_modes = system.n_modes[chassis]
    coupling = params.bodies[chassis].coupling if n_modes else None
    for corner in CORNERS:
        pts_in = [params.points[system.point_index(f"{corner}.{n}")] for n in INNER_POINTS]
        inner.append(jnp.stack([p.position for p in pts_in]))
        if n_modes:
            shapes.append(coupling * jnp.stack([p.shapes for p in pts_in]))
        else:
            shapes.append(jnp.zeros((5, 3, 0)))
        rack.append(np.asarray([float(system.point_input[system.point_index(f"{corner}.{n}")] >= 0)
                                for n in INNER_POINTS]))
        outer.append(jnp.stack([params.points[system.point_index(f"{corner}.{n}")].position for n in OUTER_POINTS]))
        lengths.append(jnp.stack([params.joints[system.joint_names.index(f"{corner}.{name}")].length
                                  for name, _, _ in QUARTER_CAR_LINKS]))
    return CornerGeometry(inner=jnp.stack(inner), inner_shapes=jnp.stack(shapes), rack=jnp.asarray(np.stack(rack)),
                          outer=jnp.stack(outer), lengths=jnp.stack(lengths), centre=centres)


def _elementary(axis: int, c, s, o, z) -> list:
    """Rows of the rotation about ``axis`` with cosine ``c``, sine ``s`` (``o``, ``z``: one
    and zero; with ``(-s, c, z, z)`` its derivative with respect to the angle)."""
    if axis == 0:
        return [[o, z, z], [z, c, -s], [z, s, c]]
    if axis == 1:
        return [[c, z, s], [z, o, z], [-s, z, c]]
    return [[c, -s, z], [s, c, z], [z, z, o]]


def _matmul(a: list, b: list) -> list:
    """``a @ b`` of 3 x 3 matrices held as rows of arrays (elementwise: XLA fuses it)."""
    return [[a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j] for j in range(3)] for i in range(3)]


def _rotation_zxy(angles, derivatives: bool = False) -> list:
    """``rotation_matrix("zxy", angles)`` as rows of arrays; with ``derivatives`` also its
    derivatives with respect to the three angles: ``[A, dA/d0, dA/d1, dA/d2]``."""
    factors, slopes = [], []
    for axis, angle in zip((2, 0, 1), angles, strict=True):
        s, c = sin_cos(angle)
        o, z = jnp.ones_like(c), jnp.zeros_like(c)
        factors.append(_elementary(axis, c, s, o, z))
        slopes.append(_elementary(axis, -s, c, z, z))
    out = [_matmul(_matmul(factors[0], factors[1]), factors[2])]
    if derivatives:
        for k in range(3):
            f = [slopes[i] if i == k else factors[i] for i in range(3)]
            out.append(_matmul(_matmul(f[0], f[1]), f[2]))
    return out


def _turn(a: list, p) -> list:
    """Components of ``a @ p`` for the rows ``p`` (5, 3)."""
    return [a[i][0] * p[:, 0] + a[i][1] * p[:, 1] + a[i][2] * p[:, 2] for i in range(3)]


def _links(w, geometry: CornerGeometry, travel, rack, pivots, outer=None):
    """Components ``(d_x, d_y, d_z)`` (5,) each of inner pivot minus outer point (m, chassis
    axes); ``outer``: the upright points already turned by the pose's rotation (components),
    where the caller has them."""
    if outer is None:
        outer = _turn(_rotation_zxy([w[2], w[3], w[4]])[0], geometry.outer)
    r = [geometry.centre[0] + w[0], geometry.centre[1] + w[1], geometry.centre[2] + travel]
    shift = [0.0, rack * geometry.rack, 0.0]
    return [pivots[:, i] + shift[i] - r[i] - outer[i] for i in range(3)]


def link_residual(w, geometry: CornerGeometry, travel, rack, pivots):
    """The five link equations of one corner, ``(|d|^2 - l^2) / (2 l)`` (m). ``pivots``:
    the inner pivots (5, 3) with the chassis deformation, before the rack."""
    dx, dy, dz = _links(w, geometry, travel, rack, pivots)
    return (dx * dx + dy * dy + dz * dz - geometry.lengths**2) / (2.0 * geometry.lengths)


def link_jacobians(w, geometry: CornerGeometry, travel, rack, pivots):
    """``(residual, d residual / dw (5, 5), d/d travel (5,), d/d rack (5,), d/d pivots
    (5, 3))`` of :func:`link_residual`, in closed form (``d residual / d d = d / l``). The
    rotation and its three derivatives turn the upright points in one product: written
    elementwise, XLA fused the rotation's sines and cosines into every entry of the
    Jacobians and recomputed them there (docs/manoeuvre.md, "Speed")."""
    rotations = jnp.stack([jnp.stack([jnp.stack(row) for row in a]) for a in _rotation_zxy([w[2], w[3], w[4]], True)])
    turned = jnp.einsum("aij,lj->ali", rotations, geometry.outer)  # (4, 5, 3): A p and its derivatives
    r = jnp.stack([geometry.centre[0] + w[0], geometry.centre[1] + w[1], geometry.centre[2] + travel])
    shift = jnp.stack([jnp.zeros_like(geometry.rack), rack * geometry.rack, jnp.zeros_like(geometry.rack)], axis=1)
    d = pivots + shift - r[None, :] - turned[0]
    inv = 1.0 / geometry.lengths
    residual = (jnp.sum(d * d, axis=1) - geometry.lengths**2) * (0.5 * inv)
    unit = d * inv[:, None]
    jac_w = jnp.concatenate([-unit[:, :2], -jnp.einsum("li,ali->la", unit, turned[1:])], axis=1)
    return residual, jac_w, -unit[:, 2], geometry.rack * unit[:, 1], unit


#: The two axes each elementary rotation turns, in its own order (x: y -> z, y: z -> x, z: x -> y).
_PLANE = {0: (1, 2), 1: (2, 0), 2: (0, 1)}


def _rotate_jet(axis: int, angle, rate, jet):
    """The jet (value, first and second derivative along the motion; each three component
    arrays) of ``R v`` for the rotation ``R`` about ``axis`` by ``angle`` turning at ``rate``
    (rad per unit of the motion), from the jet of ``v`` (``None`` for a zero derivative).
    ``R' u`` turns the rotated vector a quarter turn in the plane of the rotation and
    ``R'' u`` is minus its part in that plane."""
    i, j = _PLANE[axis]
    s, c = sin_cos(angle)

    def turn(v):
        out = list(v)
        out[i], out[j] = c * v[i] - s * v[j], s * v[i] + c * v[j]
        return out

    def quarter(u):
        out = [0.0, 0.0, 0.0]
        out[i], out[j] = -u[j], u[i]
        return out

    value, first, second = jet
    rv = turn(value)
    d1 = [rate * a for a in quarter(rv)]
    d2 = [0.0, 0.0, 0.0]
    d2[i], d2[j] = -rate * rate * rv[i], -rate * rate * rv[j]
    if first is not None:
        r1 = turn(first)
        d1 = [a + b for a, b in zip(d1, r1, strict=True)]
        d2 = [a + 2.0 * rate * b for a, b in zip(d2, quarter(r1), strict=True)]
    if second is not None:
        d2 = [a + b for a, b in zip(d2, turn(second), strict=True)]
    return rv, d1, d2


def link_curvature(w, w_dot, geometry: CornerGeometry, travel, travel_rate, rack, rack_rate, pivots, pivot_rates):
    """Second derivative (m per unit of the motion squared) of :func:`link_residual` of one
    corner along the straight motion ``w + e w_dot``, ``travel + e travel_rate``,
    ``rack + e rack_rate``, ``pivots + e pivot_rates`` at ``e = 0``, in closed form: with
    ``d`` the links' vectors, ``(d' . d' + d . d'') / l``, where only the upright's rotation
    makes ``d''`` non-zero. (As a nested forward-mode derivative it made the car's
    vector-Jacobian product 1.8 times as dear: docs/manoeuvre.md, "Speed".)"""
    jet = ([geometry.outer[:, k] for k in range(3)], None, None)
    for axis, k in ((1, 4), (0, 3), (2, 2)):  # "zxy": the y rotation acts first
        jet = _rotate_jet(axis, w[k], w_dot[k], jet)
    turned, turned_rate, turned_acc = jet
    d = _links(w, geometry, travel, rack, pivots, outer=turned)
    centre_rate, shift_rate = [w_dot[0], w_dot[1], travel_rate], [0.0, rack_rate * geometry.rack, 0.0]
    total = 0.0
    for k in range(3):
        d_rate = pivot_rates[:, k] + shift_rate[k] - centre_rate[k] - turned_rate[k]
        total = total + d_rate * d_rate - d[k] * turned_acc[k]
    return total / geometry.lengths


#: Pivot rows of the elimination, fixed: the order partial pivoting picks for the library
#: car's link Jacobian over the map's range (the alternative it picks at some states swaps
#: the last two rows; the fixed order's pivots stay above 0.8 of partial pivoting's,
#: condition numbers 40-120).
PIVOT_ORDER = (2, 3, 4, 1, 0)


def lu_small(a: Float[Array, "5 5"]) -> tuple[list, list, list]:
    """Elimination of a link Jacobian in the fixed row order :data:`PIVOT_ORDER`, unrolled
    into elementwise operations (XLA fuses them; a LAPACK call, or a pivot search, per
    corner and solve cost more than the arithmetic): ``(rows of U, multipliers, 1 /
    pivots)``."""
    n = len(PIVOT_ORDER)
    rows = [a[i] for i in PIVOT_ORDER]
    multipliers, inverse = [], []
    for k in range(n):
        inverse.append(1.0 / rows[k][k])
        factors = [rows[i][k] * inverse[k] for i in range(k + 1, n)]
        rows[k + 1:] = [rows[i] - f * rows[k] for i, f in zip(range(k + 1, n), factors, strict=True)]
        multipliers.append(factors)
    return rows, multipliers, inverse


def lu_solve_small(lu, b):
    """``a^-1 b`` from :func:`lu_small`'s factors; ``b`` a vector or a matrix of columns
    (linear in ``b``)."""
    rows, multipliers, inverse = lu
    n = len(rows)
    b = [b[i] for i in PIVOT_ORDER]
    for k in range(n):
        b[k + 1:] = [b[i] - f * b[k] for i, f in zip(range(k + 1, n), multipliers[k], strict=True)]
    x = [None] * n
    for k in reversed(range(n)):
        acc = b[k]
        for j in range(k + 1, n):
            acc = acc - rows[k][j] * x[j]
        x[k] = acc * inverse[k]
    return jnp.stack(x)


def solve_small(a: Float[Array, "5 5"], b):
    """``a^-1 b`` for a link Jacobian ``a`` (see :func:`lu_small`); ``b`` a vector or a
    matrix of columns."""
    return lu_solve_small(lu_small(a), b)


def _newton(w, geometry, travel, rack, pivots, iterations: int, unroll: bool = True):
    def step(_, w):
        res, jac = link_jacobians(w, geometry, travel, rack, pivots)[:2]
        return w - solve_small(jac, res)

    return jax.lax.fori_loop(0, iterations, step, w, unroll=unroll)


@jax.custom_jvp
def solve_pose(guess, geometry: CornerGeometry, travel, rack, pivots):
    """``w`` of one corner (see the module docs) by Newton from ``guess``; derivatives by the
    implicit function theorem."""
    return _newton(guess, geometry, travel, rack, pivots, POSE_ITERATIONS)


@solve_pose.defjvp
def _solve_pose_jvp(primals, tangents):
    guess, geometry, travel, rack, pivots = primals
    _, d_geometry, d_travel, d_rack, d_pivots = tangents
    w = solve_pose(guess, geometry, travel, rack, pivots)
    jac = link_jacobians(w, geometry, travel, rack, pivots)[1]
    _, d_res = jax.jvp(lambda g, t, r, p: link_residual(w, g, t, r, p), (geometry, travel, rack, pivots),
                       (d_geometry, d_travel, d_rack, d_pivots))
    return w, -solve_small(jac, d_res)


# ---- the kinematic map (the guess) ------------------------------------------------------


class KinematicMap(eqx.Module):
    """Chebyshev coefficients (4 corners, degree+1 in travel, degree+1 in rack, 5) of the
    pose ``w`` on the undeformed chassis over ``MAP_TRAVEL`` x ``MAP_RACK``."""

    coefficients: Float[Array, "4 nt nr 5"]


def _nodes(lo, hi, degree):
    k = np.arange(degree + 1)
    x = np.cos(np.pi * (k + 0.5) / (degree + 1))  # Chebyshev points of the first kind
    return x, 0.5 * (lo + hi) + 0.5 * (hi - lo) * x


def _fit_matrix(x, degree):
    """Discrete Chebyshev transform on first-kind nodes: coefficients = F @ values."""
    t = np.cos(np.outer(np.arange(degree + 1), np.arccos(x)))
    f = 2.0 / (degree + 1) * t
    f[0] /= 2.0
    return f


def _chebyshev(x, degree):
    """``[T_0(x), ..., T_degree(x)]`` as ``cos(k arccos x)`` (one fused loop; the
    three-term recurrence is a chain of separate operations). No derivative with respect to
    ``x``: the guess only starts the solve, whose derivatives do not depend on it."""
    angle = arccos(jax.lax.stop_gradient(x))
    return cos(jnp.arange(degree + 1.0)[:, None] * angle[None, :])


def _scaled(v, lo, hi):
    return (2.0 * v - (lo + hi)) / (hi - lo)


def build_map(geometry: CornerGeometry) -> KinematicMap:
    """Fit the map from exact solves on a Chebyshev grid (JAX operations: rebuilt, and
    differentiable, whenever the geometry changes). Travel is swept outward from the design
    position so each solve starts next to a solved neighbour."""
    (nt, nr) = MAP_DEGREE
    xt, travel = _nodes(*MAP_TRAVEL, nt)
    xr, rack = _nodes(*MAP_RACK, nr)
    zero_pivots = geometry.inner

    def corner(g, pivots):
        def along_rack(r):
            def sweep(w, t):
                w = _newton(w, g, t, r, pivots, MAP_ITERATIONS, unroll=False)
                return w, w

            order = np.argsort(np.abs(travel))
            w0 = jnp.zeros((5,))
            # outward from the design: one pass up, one pass down, each warm-started
            up = [i for i in order if travel[i] >= 0]
            down = [i for i in order if travel[i] < 0]
            _, w_up = jax.lax.scan(sweep, w0, jnp.asarray(travel[up]))
            _, w_down = jax.lax.scan(sweep, w0, jnp.asarray(travel[down]))
            w_all = jnp.concatenate([w_up, w_down])
            return w_all[np.argsort(np.asarray(up + down))]

        return jax.vmap(along_rack, out_axes=1)(jnp.asarray(rack))  # (nt+1, nr+1, 5)

    values = jax.vmap(corner)(geometry, zero_pivots)
    ft, fr = _fit_matrix(xt, nt), _fit_matrix(xr, nr)
    return KinematicMap(coefficients=jnp.einsum("ai,bj,kijw->kabw", ft, fr, values))


def map_guess(kmap: KinematicMap, travel, rack) -> Float[Array, "4 5"]:
    """The map's pose guess of the four corners at their travels (4,) and rack travels (4,)."""
    nt, nr = MAP_DEGREE
    tt = _chebyshev(jnp.clip(_scaled(travel, *MAP_TRAVEL), -1.0, 1.0), nt)  # (nt+1, 4)
    tr = _chebyshev(jnp.clip(_scaled(rack, *MAP_RACK), -1.0, 1.0), nr)
    return jnp.einsum("ak,bk,kabw->kw", tt, tr, kmap.coefficients)


def corner_poses(geometry: CornerGeometry, kmap: KinematicMap, travel, rack, modes):
    """Poses ``w`` (4, 5) of the four uprights at travels (4,), rack (scalar, m) and chassis
    modal coordinates ``modes``."""
    pivots = geometry.inner + jnp.einsum("kpim,m->kpi", geometry.inner_shapes, modes)
    racks = jnp.broadcast_to(rack, (4,))
    guess = map_guess(kmap, travel, racks)
    return jax.vmap(solve_pose)(guess, geometry, travel, racks, pivots)


class CornerMotion(eqx.Module):
    """Motion of the four uprights relative to the chassis frame (leading axis: corners).
    ``w`` poses (see the module docs); ``w_dot`` their rates; ``w_acc0`` their
    accelerations when the travel and modal accelerations are zero (the rack's included);
    ``sens`` (4, 5, 2 + n) the sensitivities ``dw/d[travel, rack, modes]``."""

    w: Float[Array, "4 5"]
    w_dot: Float[Array, "4 5"]
    w_acc0: Float[Array, "4 5"]
    sens: Float[Array, "4 5 m"]


def corner_motion(geometry: CornerGeometry, kmap: KinematicMap, travel, rack, modes, travel_rate, rack_rate,
                  modal_rate, rack_acc) -> CornerMotion:
    """Poses, rates and velocity-product accelerations of the four uprights at travels
    (4,) and rates, rack travel, rate and acceleration (scalars, m), modal coordinates and
    rates. Rates by the implicit function theorem on the link equations, the
    velocity-product terms by their second directional derivative along the motion
    (:func:`link_curvature`)."""
    w = corner_poses(geometry, kmap, travel, rack, modes)
    pivots = geometry.inner + jnp.einsum("kpim,m->kpi", geometry.inner_shapes, modes)
    pivot_rates = jnp.einsum("kpim,m->kpi", geometry.inner_shapes, modal_rate)

    def one(g, w, t, piv, t_rate, piv_rate):
        _, jac_w, jac_t, jac_s, jac_piv = link_jacobians(w, g, t, rack, piv)
        jac_p = jnp.einsum("li,lim->lm", jac_piv, g.inner_shapes)
        sens = -solve_small(jac_w, jnp.concatenate([jac_t[:, None], jac_s[:, None], jac_p], axis=1))
        w_dot = sens @ jnp.concatenate([jnp.stack([t_rate, rack_rate]), modal_rate])
        curvature = link_curvature(w, w_dot, g, t, t_rate, rack, rack_rate, piv, piv_rate)
        w_acc0 = sens[:, 1] * rack_acc - solve_small(jac_w, curvature)
        return sens, w_dot, w_acc0

    sens, w_dot, w_acc0 = jax.vmap(one)(geometry, w, travel, pivots, travel_rate, pivot_rates)
    return CornerMotion(w=w, w_dot=w_dot, w_acc0=w_acc0, sens=sens)


def pose_residual(geometry: CornerGeometry, travel, rack, modes, w) -> Float[Array, ""]:
    """Largest link residual (m) of solved poses: what the fixed Newton count left."""
    pivots = geometry.inner + jnp.einsum("kpim,m->kpi", geometry.inner_shapes, modes)
    racks = jnp.broadcast_to(rack, (4,))
    res = jax.vmap(link_residual)(w, geometry, travel, racks, pivots)
    return jnp.max(jnp.abs(res))
