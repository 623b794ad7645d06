"""Force elements: one kinematics pass per evaluation, elements as Equinox modules, and
their point forces and torques gathered into generalised forces in one call.

Every element sees the same :class:`Kinematics` (body poses, every point's global position
and velocity, the material orientation and angular velocity at every point, the input
values and rates) and returns :class:`ElementForces`: forces and torques at points
(``[n_points, 3]``, global axes, N and N m) and the derivatives of its auxiliary states.
The generalised forces are the transpose of the point-velocity map applied to them, so a
force at a point of a flexible body loads its modes through the translational mode shapes
and a torque through the rotational ones.
"""

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import float_field
from .._trig import arctan2
from ._kinematics import _add_modal, _body_rows, _frames, points_global, points_local
from ._system import System, SystemParams


class Kinematics(eqx.Module):
    """Everything force elements read at one state (global axes, SI units).

    ``t`` time (s); ``q`` coordinates; ``v`` body velocities; ``u``, ``u_dot`` inputs and
    rates; ``origins`` (nb, 3) and ``rotations`` (nb, 3, 3) of the body frames; ``x``, ``xd``
    (np, 3) point positions (m) and velocities (m/s, input rates included); ``point_rotations``
    (np, 3, 3) material orientation at each point; ``point_omega`` (np, 3) its angular
    velocity (rad/s); ``modal`` the modal coordinates of every body (tuple)."""

    t: Float[Array, ""]
    q: Float[Array, " nq"]
    v: Float[Array, " nv"]
    u: Float[Array, " ni"]
    u_dot: Float[Array, " ni"]
    origins: Float[Array, "nb 3"]
    rotations: Float[Array, "nb 3 3"]
    x: Float[Array, "np 3"]
    xd: Float[Array, "np 3"]
    point_rotations: Float[Array, "np 3 3"]
    point_omega: Float[Array, "np 3"]
    modal: tuple


class ElementForces(eqx.Module):
    """What one element applies: ``forces`` and ``torques`` at points (np, 3; N, N m, global
    axes) and ``aux_dot`` (its auxiliary state derivatives)."""

    forces: Float[Array, "np 3"]
    torques: Float[Array, "np 3"]
    aux_dot: Float[Array, " na"]


class AbstractForceElement(eqx.Module):
    """A force element. Static ``aux_names`` name its first-order states (empty for none);
    ``__call__(kin, aux, system)`` returns :class:`ElementForces` for one state (``aux``:
    this element's slice of the auxiliary states)."""

    aux_names: eqx.AbstractVar[tuple[str, ...]]

    @abc.abstractmethod
    def __call__(self, kin: Kinematics, aux, system: System) -> ElementForces:
        """Point forces/torques and auxiliary-state derivatives at one state."""


def zero_forces(kin: Kinematics, n_aux: int = 0) -> ElementForces:
    """An :class:`ElementForces` with nothing in it (start here and ``.at[k].add``)."""
    zeros = jnp.zeros_like(kin.x)
    return ElementForces(forces=zeros, torques=zeros, aux_dot=jnp.zeros((n_aux,), kin.x.dtype))


class SpringDamper(AbstractForceElement):
    """Linear spring-damper between points ``i`` and ``j`` along their line: tension
    ``k (l - l0) + c l_dot + preload`` (N) pulls them together. ``k`` N/m, ``c`` Ns/m,
    ``l0`` free length (m), ``preload`` (N). Build with :meth:`between`."""

    i: int = eqx.field(static=True)
    j: int = eqx.field(static=True)
    k: Float[Array, ""] = float_field()
    c: Float[Array, ""] = float_field()
    l0: Float[Array, ""] = float_field()
    preload: Float[Array, ""] = float_field(default=0.0)
    aux_names: tuple[str, ...] = eqx.field(static=True, default=())

    @classmethod
    def between(cls, system: System, p: str, q: str, k, c, l0, preload=0.0) -> "SpringDamper":
        return cls(system.point_index(p), system.point_index(q), k, c, l0, preload)

    def __call__(self, kin, aux, system):
        d = kin.x[self.j] - kin.x[self.i]
        length = jnp.sqrt(jnp.sum(d * d))
        n = d / length
        rate = n @ (kin.xd[self.j] - kin.xd[self.i])
        tension = self.k * (length - self.l0) + self.c * rate + self.preload
        out = zero_forces(kin)
        f = out.forces.at[self.i].add(tension * n).at[self.j].add(-tension * n)
        return eqx.tree_at(lambda e: e.forces, out, f)


class Bushing(AbstractForceElement):
    """Linear bushing between point ``i`` (body A) and point ``j`` (body B): the force on
    ``j`` is ``-(K (x_j - x_i) + C (xd_j - xd_i))`` with diagonal stiffness ``k`` (N/m) and
    damping ``c`` (Ns/m) in the axes of ``i``'s material frame; the torque on ``j`` is
    ``-(kr theta + cr omega_rel)`` with the small relative rotation ``theta`` (rad) and
    rotational rates ``kr`` (N m/rad), ``cr`` (N m s/rad). Equal and opposite on ``i``."""

    i: int = eqx.field(static=True)
    j: int = eqx.field(static=True)
    k: Float[Array, "3"] = float_field()
    c: Float[Array, "3"] = float_field()
    kr: Float[Array, "3"] = float_field(default=(0.0, 0.0, 0.0))
    cr: Float[Array, "3"] = float_field(default=(0.0, 0.0, 0.0))
    aux_names: tuple[str, ...] = eqx.field(static=True, default=())

    @classmethod
    def between(cls, system: System, p: str, q: str, k, c, kr=(0.0, 0.0, 0.0), cr=(0.0, 0.0, 0.0)) -> "Bushing":
        return cls(system.point_index(p), system.point_index(q), k, c, kr, cr)

    def __call__(self, kin, aux, system):
        a = kin.point_rotations[self.i]
        d = a.T @ (kin.x[self.j] - kin.x[self.i])
        dd = a.T @ (kin.xd[self.j] - kin.xd[self.i])
        rel = a.T @ kin.point_rotations[self.j]
        theta = 0.5 * jnp.stack([rel[2, 1] - rel[1, 2], rel[0, 2] - rel[2, 0], rel[1, 0] - rel[0, 1]])
        w = a.T @ (kin.point_omega[self.j] - kin.point_omega[self.i])
        force = a @ (self.k * d + self.c * dd)
        torque = a @ (self.kr * theta + self.cr * w)
        out = zero_forces(kin)
        return ElementForces(
            forces=out.forces.at[self.i].add(force).at[self.j].add(-force),
            torques=out.torques.at[self.i].add(torque).at[self.j].add(-torque),
            aux_dot=out.aux_dot,
        )


class TorsionSpring(AbstractForceElement):
    """Torsion spring-damper between the material frames at points ``i`` and ``j`` about the
    unit ``axis`` (axes of ``i``'s frame): torque ``kt (phi - phi0) + ct phi_dot`` (N m)
    with the relative rotation ``phi`` (rad, small-angle/atan2 of the relative rotation
    about the axis), e.g. an anti-roll bar or a revolute joint's spring."""

    i: int = eqx.field(static=True)
    j: int = eqx.field(static=True)
    axis: Float[Array, "3"] = float_field()
    kt: Float[Array, ""] = float_field()
    ct: Float[Array, ""] = float_field()
    phi0: Float[Array, ""] = float_field(default=0.0)
    aux_names: tuple[str, ...] = eqx.field(static=True, default=())

    @classmethod
    def between(cls, system: System, p: str, q: str, axis, kt, ct, phi0=0.0) -> "TorsionSpring":
        axis = np.asarray(axis, dtype=np.float64)
        return cls(system.point_index(p), system.point_index(q), axis / np.linalg.norm(axis), kt, ct, phi0)

    def __call__(self, kin, aux, system):
        a = kin.point_rotations[self.i]
        rel = a.T @ kin.point_rotations[self.j]
        n = self.axis
        # a unit vector normal to the axis, and the angle of its image about the axis
        e = jnp.cross(n, jnp.eye(3, dtype=n.dtype)[jnp.argmin(jnp.abs(n))])
        e = e / jnp.linalg.norm(e)
        re = rel @ e
        phi = arctan2(jnp.dot(jnp.cross(e, re), n), jnp.dot(e, re))
        phi_dot = n @ (a.T @ (kin.point_omega[self.j] - kin.point_omega[self.i]))
        torque = a @ (n * (self.kt * (phi - self.phi0) + self.ct * phi_dot))
        out = zero_forces(kin)
        return eqx.tree_at(lambda o: o.torques, out, out.torques.at[self.i].add(torque).at[self.j].add(-torque))


class FirstOrderLag(AbstractForceElement):
    """A first-order lag state ``x`` (no force): ``tau x_dot = gain * signal(kin) - x`` with
    ``signal`` a static function of the kinematics (e.g. a point's velocity component, or
    an input value). Useful for tyre relaxation-like states and driver filters."""

    signal: object = eqx.field(static=True)
    tau: Float[Array, ""] = float_field()
    gain: Float[Array, ""] = float_field(default=1.0)
    aux_names: tuple[str, ...] = eqx.field(static=True, default=("x",))

    def __call__(self, kin, aux, system):
        out = zero_forces(kin, 1)
        x_dot = (self.gain * self.signal(kin) - aux[0]) / self.tau
        return eqx.tree_at(lambda o: o.aux_dot, out, jnp.reshape(x_dot, (1,)))


def aux_offsets(elements) -> tuple[int, ...]:
    """Static offsets of each element's auxiliary states in the ``aux`` vector."""
    return tuple(int(x) for x in np.cumsum([0] + [len(e.aux_names) for e in elements]))


def aux_names(elements, names: tuple[str, ...] | None = None) -> tuple[str, ...]:
    """``element.state`` names of the auxiliary states (``element`` = its index or name)."""
    labels = names if names is not None else tuple(f"e{k}" for k in range(len(elements)))
    return tuple(f"{labels[k]}.{a}" for k, e in enumerate(elements) for a in e.aux_names)


def kinematics(system: System, params: SystemParams, q, vs, poses, u, u_dot, t) -> Kinematics:
    """The one kinematics pass of an evaluation (positions, velocities, point frames)."""
    dtype = q.dtype
    frames = _frames(poses, dtype)
    local = points_local(system, params, poses, u)
    x = points_global(system, frames, local)
    xd = _point_velocities(system, params, frames, vs, local, u_dot)
    rots, omega = _point_frames(system, params, frames, poses, vs)
    return Kinematics(
        t=t,
        q=q,
        v=jnp.concatenate(vs),
        u=u,
        u_dot=u_dot,
        origins=frames[0][1:],
        rotations=frames[1][1:],
        x=x,
        xd=xd,
        point_rotations=rots,
        point_omega=omega,
        modal=tuple(p[2] for p in poses),
    )


def _stack_body(system, vs, part, dtype):
    zero = jnp.zeros((3,), dtype)
    return jnp.stack([zero] + [v[part] for v in vs])


def _point_velocities(system, params, frames, vs, local, u_dot):
    """Global point velocities: rigid motion, modal rates and input rates."""
    dtype = local.dtype
    rows = _body_rows(system)
    us, ws = _stack_body(system, vs, slice(0, 3), dtype), _stack_body(system, vs, slice(3, 6), dtype)
    rel = us[rows] + jnp.cross(ws[rows], local)
    rel = _add_modal(system, params, rel, [v[6:] for v in vs])
    idx = [k for k, i in enumerate(system.point_input) if i >= 0]
    if idx:
        dirs = jnp.stack([params.points[k].input_direction for k in idx])
        rates = u_dot[np.asarray([system.point_input[k] for k in idx])]
        rel = rel.at[np.asarray(idx)].add(rates[:, None] * dirs)
    return jnp.einsum("kij,kj->ki", frames[1][rows], rel)


def _add_modal_rotation(system, params, out, modal_values):
    """``out[k] += coupling * Psi_r_k @ modal_values[body(k)]`` for points on flexible bodies."""
    for b in range(system.n_bodies):
        idx = [k for k, pb in enumerate(system.point_body) if pb == b]
        if system.n_modes[b] == 0 or not idx:
            continue
        shapes = jnp.stack([params.points[k].rotation_shapes for k in idx])
        out = out.at[np.asarray(idx)].add(params.bodies[b].coupling * jnp.einsum("kim,m->ki", shapes, modal_values[b]))
    return out


def _skew_batch(w):
    z = jnp.zeros_like(w[:, 0])
    return jnp.stack(
        [
            jnp.stack([z, -w[:, 2], w[:, 1]], -1),
            jnp.stack([w[:, 2], z, -w[:, 0]], -1),
            jnp.stack([-w[:, 1], w[:, 0], z], -1),
        ],
        axis=1,
    )


def _point_frames(system, params, frames, poses, vs):
    """Material orientation ``A (I + skew(theta))`` and global angular velocity at every point."""
    dtype = frames[0].dtype
    rows = _body_rows(system)
    n = len(system.point_names)
    theta = _add_modal_rotation(system, params, jnp.zeros((n, 3), dtype), [p[2] for p in poses])
    a = frames[1][rows]
    rots = a + jnp.einsum("kij,kjl->kil", a, _skew_batch(theta))
    ws = _stack_body(system, vs, slice(3, 6), dtype)[rows]
    ws = _add_modal_rotation(system, params, ws, [v[6:] for v in vs])
    return rots, jnp.einsum("kij,kj->ki", a, ws)


def generalised_forces(system: System, params: SystemParams, q, poses, forces, torques) -> Float[Array, " nv"]:
    """``Q`` (body-velocity coordinates) of point forces and torques (np, 3; global axes):
    the transpose of the map from body velocities to point velocities and angular
    velocities, applied in one call (translational and rotational mode shapes included)."""
    dtype = q.dtype
    frames = _frames(poses, dtype)
    local = points_local(system, params, poses, jnp.zeros((system.n_inputs,), dtype))

    def point_rates(v):
        vs = [v[system.v_offsets[i] : system.v_offsets[i + 1]] for i in range(system.n_bodies)]
        xd = _point_velocities(system, params, frames, vs, local, jnp.zeros((system.n_inputs,), dtype))
        rows = _body_rows(system)
        ws = _stack_body(system, vs, slice(3, 6), dtype)[rows]
        ws = _add_modal_rotation(system, params, ws, [vi[6:] for vi in vs])
        return xd, jnp.einsum("kij,kj->ki", frames[1][rows], ws)

    transpose = jax.linear_transpose(point_rates, jnp.zeros((system.n_v,), dtype))
    return transpose((forces, torques))[0]


def element_forces(system: System, params: SystemParams, elements, kin: Kinematics, aux):
    """Sum of every element's point forces and torques, and the stacked ``aux_dot``."""
    offsets = aux_offsets(elements)
    forces = jnp.zeros_like(kin.x)
    torques = jnp.zeros_like(kin.x)
    aux_dot = []
    for k, element in enumerate(elements):
        out = element(kin, aux[offsets[k] : offsets[k + 1]], system)
        forces, torques = forces + out.forces, torques + out.torques
        aux_dot.append(out.aux_dot)
    aux_dot = jnp.concatenate(aux_dot) if aux_dot else jnp.zeros((0,), kin.x.dtype)
    return forces, torques, aux_dot

