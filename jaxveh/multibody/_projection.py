"""Velocity projection (coordinate reduction, eqs. 5.52-5.62) and the reduced equations of
motion (5.61); Lagrange multipliers; rank and mass-matrix checks.

With joint velocities ``y`` (eq. 5.47), ``[Phi_q B T; P] y = [b; z]`` (5.54) is factorised
once per evaluation (LU) and reused for ``R``, ``S b`` and ``S c`` (5.62); ``S`` itself is
never formed. Drift control (documented choice): the velocity equation uses
``b = -Phi_t - kappa Phi`` so that along every solution ``Phi_dot = -kappa Phi`` (a first
order, Baumgarte-type stabilisation at velocity level, exact in the projection and free of
iterations); ``c`` is the consistent time derivative, so ``z`` still obeys eq. (5.61)
exactly when ``Phi = 0``.
"""

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._dynamics import internal_forces, mass_matrix
from ._errors import RedundantConstraintError, SingularMassMatrixError
from ._forces import Kinematics, element_forces, generalised_forces, kinematics
from ._inputs import AbstractInputs, as_inputs
from ._kinematics import body_poses, body_velocities, constraint_rates, constraints, qdot_from_velocities
from ._system import System, SystemParams

Inputs = Callable[[Float[Array, ""]], Float[Array, " ni"]] | AbstractInputs
External = Callable[..., Float[Array, " nv"]]


def _empty(dtype):
    return jnp.zeros((0,), dtype)


def input_state(system: System, inputs, t, q, aux=None):
    """``(u, u_dot)``: rheonomic input values and rates at ``(t, q, aux)`` (empty vectors for
    a system without inputs)."""
    if system.n_inputs == 0:
        return _empty(q.dtype), _empty(q.dtype)
    law = as_inputs(inputs)
    if law is None:
        raise ValueError(f"system has inputs {system.input_names}; pass an `inputs(t)` function or an input law")
    aux = _empty(q.dtype) if aux is None else aux
    u, u_dot = law.value(t, q, aux), law.rate(t, q, aux)
    if u.shape != (system.n_inputs,) or u_dot.shape != (system.n_inputs,):
        raise ValueError(f"inputs must give {system.n_inputs} values {system.input_names}, got shape {u.shape}")
    return u, u_dot


def input_values(system: System, inputs, t, dtype=jnp.float64, q=None, aux=None):
    """Rheonomic input values ``u``; an empty vector for a system without inputs."""
    if system.n_inputs == 0:
        return _empty(dtype)
    law = as_inputs(inputs)
    if law is None:
        raise ValueError(f"system has inputs {system.input_names}; pass an `inputs(t)` function or an input law")
    q = _empty(dtype) if q is None else q
    return jnp.asarray(law.value(t, q, _empty(dtype) if aux is None else aux), dtype=dtype)


class Projection(eqx.Module):
    """Kinematic quantities at one state (thesis Table 5.3 and eqs. 5.54-5.62).

    ``phi`` constraint residuals, ``phi_y = Phi_q B T``, ``T`` recursion matrix, ``R``
    projection (null-space) matrix, ``Sb`` particular velocity solution, ``lu`` the LU
    factors of the dependent-velocity block of ``Phi_q B T`` (see :func:`solve_s`).
    ``B T`` itself: :func:`velocity_matrix`.
    """

    phi: Float[Array, " m"]
    phi_y: Float[Array, "m ny"]
    T: Float[Array, "nv ny"]
    R: Float[Array, "ny ndof"]
    Sb: Float[Array, " ny"]
    lu: tuple


def _jacobians(system, params, q, u, u_dot):
    """``Phi``, ``Phi_t = Phi_u u_dot``, ``T`` and ``Phi_q B T`` at ``q`` and inputs ``u``.

    ``Phi_q B T`` is the Jacobian of the explicit constraint rates (linear in the body
    velocities) composed with the recursion, so only one forward pass with ``n_y`` tangents
    through cheap linear maps is needed; the rotation matrices are not differentiated.
    """
    phi, phi_t = jax.jvp(lambda uu: constraints(system, params, q, uu), (u,), (u_dot,))
    poses = body_poses(system, params, q)

    def linear(y):
        vs = body_velocities(system, params, q, y, poses)
        return jnp.concatenate(vs), constraint_rates(system, params, poses, vs, u)

    t_mat, phi_y = jax.jacfwd(linear)(jnp.zeros((system.n_y,), q.dtype))
    return phi, phi_t, t_mat, phi_y


def _dependent(system: System) -> tuple[int, ...]:
    """Joint velocities not declared independent (static)."""
    chosen = set(system.independent)
    return tuple(k for k in range(system.n_y) if k not in chosen)


def _scatter(system: System, dep_part, ind_part):
    """Assemble a vector / matrix over ``y`` from its dependent and independent rows."""
    shape = (system.n_y,) + dep_part.shape[1:]
    out = jnp.zeros(shape, dep_part.dtype).at[jnp.asarray(_dependent(system), dtype=int)].set(dep_part)
    return out.at[jnp.asarray(system.independent, dtype=int)].set(ind_part)


def solve_s(system: System, lu, rhs):
    """``S rhs``: the particular solution of ``[Phi_q B T; P] y = [rhs; 0]``."""
    dep = jax.scipy.linalg.lu_solve(lu, rhs)
    return _scatter(system, dep, jnp.zeros((system.n_dof,) + rhs.shape[1:], rhs.dtype))


def projection(
    system: System, params: SystemParams, q, t=0.0, inputs: Inputs | None = None, kappa=0.0, aux=None
) -> Projection:
    """Constraint residuals, ``T``, ``Phi_q B T`` and the projection ``R``, ``S b`` (eq. 5.54).

    ``P`` is boolean (eq. 5.52), so ``[Phi_q B T; P]`` is solved by partitioning ``y`` into
    dependent and independent velocities: only the square block ``Phi_d`` of the dependent
    columns is LU-factorised (``m x m`` instead of ``n_y x n_y``) and reused for ``R``,
    ``S b``, ``S c`` and the multipliers. ``R`` and ``S`` are exactly those of eq. (5.55).
    """
    u, u_dot = input_state(system, inputs, jnp.asarray(t, q.dtype), q, aux)
    return _projection(system, params, q, u, u_dot, kappa)


def _projection(system, params, q, u, u_dot, kappa) -> Projection:
    phi, phi_t, t_mat, phi_y = _jacobians(system, params, q, u, u_dot)
    phi_d = phi_y[:, jnp.asarray(_dependent(system), dtype=int)]
    phi_i = phi_y[:, jnp.asarray(system.independent, dtype=int)]
    lu = jax.scipy.linalg.lu_factor(phi_d)
    b = -phi_t - kappa * phi
    sol = jax.scipy.linalg.lu_solve(lu, jnp.concatenate([b[:, None], -phi_i], axis=1))
    sol = eqx.error_if(
        sol,
        ~jnp.all(jnp.isfinite(sol)),
        "[Phi_q B T; P] is singular: redundant constraints or dependent independent velocities "
        "(call jaxveh.multibody.check_rank at this state for the names)",
    )
    zeros = jnp.zeros((system.n_dof,), q.dtype)
    r = _scatter(system, sol[:, 1:], jnp.eye(system.n_dof, dtype=q.dtype))
    return Projection(phi=phi, phi_y=phi_y, T=t_mat, R=r, Sb=_scatter(system, sol[:, 0], zeros), lu=lu)


def _refreshed(system, params, frozen: Projection, q, u, u_dot, kappa) -> Projection:
    """``frozen`` with today's residuals ``Phi`` and particular solution ``S b`` (through the
    frozen LU factors): only ``Phi`` and its input rate are evaluated, not the Jacobians."""
    phi, phi_t = jax.jvp(lambda uu: constraints(system, params, q, uu), (u,), (u_dot,))
    sb = solve_s(system, frozen.lu, -phi_t - kappa * phi)
    return Projection(phi=phi, phi_y=frozen.phi_y, T=frozen.T, R=frozen.R, Sb=sb, lu=frozen.lu)


def _velocity_constraint(system, params, y, kappa):
    """``h(q, u, w) = Phi_q B T y + Phi_u w + kappa Phi`` with ``y`` held fixed (``w`` the input rates)."""

    def h(q, u, w):
        poses = body_poses(system, params, q)
        vs = body_velocities(system, params, q, y, poses)
        phi, phi_t = jax.jvp(lambda uu: constraints(system, params, q, uu), (u,), (w,))
        return constraint_rates(system, params, poses, vs, u) + phi_t + kappa * phi

    return h


class Dynamics(eqx.Module):
    """Everything eq. (5.61) produces at one state.

    ``y`` joint velocities, ``v`` body velocities, ``q_dot``, ``z_dot`` independent
    accelerations, ``mass_matrix`` the reduced ``R^T T^T M T R``, ``internal_forces`` the
    reduced velocity/elastic/damping forces ``R^T T^T (Q_v + Q_e - M (T_dot y + T S c))``,
    ``external_forces`` the reduced gravity + applied forces, ``y_dot``, ``v_dot``, ``Sc``,
    ``multipliers`` (see :func:`multipliers`), ``aux_dot`` (auxiliary-state derivatives of
    the force elements), ``u`` / ``u_dot`` (inputs and rates) and ``kinematics`` (the
    :class:`Kinematics` the elements saw; None without elements). Under ``jit`` whatever the caller does not use
    is removed by dead-code elimination.
    """

    projection: Projection
    y: Float[Array, " ny"]
    v: Float[Array, " nv"]
    q_dot: Float[Array, " nq"]
    z_dot: Float[Array, " ndof"]
    y_dot: Float[Array, " ny"]
    v_dot: Float[Array, " nv"]
    Sc: Float[Array, " ny"]
    mass_matrix: Float[Array, "ndof ndof"]
    internal_forces: Float[Array, " ndof"]
    external_forces: Float[Array, " ndof"]
    multipliers: Float[Array, " m"]
    aux_dot: Float[Array, " na"]
    u: Float[Array, " ni"]
    u_dot: Float[Array, " ni"]
    kinematics: Kinematics | None


def dynamics(
    system: System,
    params: SystemParams,
    q,
    z,
    t=0.0,
    inputs: Inputs | None = None,
    external: External | None = None,
    args=None,
    kappa=0.0,
    elements: tuple = (),
    aux=None,
    frozen: Projection | None = None,
) -> Dynamics:
    """Reduced equations of motion (eq. 5.61) at ``(q, z, aux, t)``.

    ``elements``: force elements (:class:`AbstractForceElement`), evaluated on one shared
    :class:`Kinematics`; ``aux`` their auxiliary states. ``external(q, v, t, args)`` returns
    further applied generalised forces in ``v`` coordinates (use :func:`point_force` /
    :func:`body_torque`); gravity is built in (``params.gravity``). ``inputs``: a function
    of time or an input law (:mod:`._inputs`). ``frozen``: a :class:`Projection` computed at
    an earlier state whose ``T``, ``Phi_q B T``, ``R`` and LU factors are used instead of
    today's (see :class:`ProjectedSolver`'s ``freeze_steps``); ``Phi`` and ``S b`` are
    always today's. ``system.options`` may drop ``S b`` and ``S c`` (Table 7.2).
    """
    t = jnp.asarray(t, q.dtype)
    aux = _empty(q.dtype) if aux is None else aux
    law = as_inputs(inputs)
    u, u_dot = input_state(system, law, t, q, aux)
    proj = _projection(system, params, q, u, u_dot, kappa) if frozen is None else _refreshed(
        system, params, frozen, q, u, u_dot, kappa)
    if system.options.neglect_sb:
        proj = eqx.tree_at(lambda p: p.Sb, proj, jnp.zeros_like(proj.Sb))
    y = proj.R @ z + proj.Sb
    poses = body_poses(system, params, q)
    vs = body_velocities(system, params, q, y, poses)
    v = jnp.concatenate(vs)
    q_dot = qdot_from_velocities(system, params, q, y, vs, poses)
    q_int, q_grav = internal_forces(system, params, q, v)
    q_ext = q_grav if external is None else q_grav + external(q, v, t, args)
    kin, aux_dot = None, _empty(q.dtype)
    if elements:
        kin = kinematics(system, params, q, vs, poses, u, u_dot, t)
        forces, torques, aux_dot = element_forces(system, params, elements, kin, aux)
        q_ext = q_ext + generalised_forces(system, params, q, poses, forces, torques)
    if system.n_inputs:
        u_ddot = jax.jvp(lambda tt, qq, aa: law.rate(tt, qq, aa), (t, q, aux), (jnp.ones_like(t), q_dot, aux_dot))[1]
    else:
        u_ddot = u_dot
    h = _velocity_constraint(system, params, y, kappa)
    c = -jax.jvp(h, (q, u, u_dot), (q_dot, u_dot, u_ddot))[1]
    sc = jnp.zeros_like(y) if system.options.neglect_sc else solve_s(system, proj.lu, c)
    t_dot_y = jax.jvp(lambda qq: jnp.concatenate(body_velocities(system, params, qq, y)), (q,), (q_dot,))[1]
    a0 = proj.T @ sc + t_dot_y  # body accelerations at z_dot = 0
    tr = proj.T @ proj.R
    m_full = mass_matrix(system, params, q)
    m_red = tr.T @ m_full @ tr
    f_int = tr.T @ (q_int - m_full @ a0)
    f_ext = tr.T @ q_ext
    chol = jnp.linalg.cholesky(m_red)
    chol = eqx.error_if(
        chol,
        ~jnp.all(jnp.isfinite(chol)),
        "reduced mass matrix R^T T^T M T R is singular or not positive definite "
        "(call jaxveh.multibody.check_mass_matrix at this state for the names)",
    )
    z_dot = jax.scipy.linalg.cho_solve((chol, True), f_int + f_ext)
    v_dot = tr @ z_dot + a0
    resid = proj.T.T @ (q_int + q_ext - m_full @ v_dot)
    lam = jax.scipy.linalg.lu_solve(proj.lu, resid[jnp.asarray(_dependent(system), dtype=int)], trans=1)
    return Dynamics(
        projection=proj,
        y=y,
        v=v,
        q_dot=q_dot,
        z_dot=z_dot,
        y_dot=proj.R @ z_dot + sc,
        v_dot=v_dot,
        Sc=sc,
        mass_matrix=m_red,
        internal_forces=f_int,
        external_forces=f_ext,
        multipliers=lam,
        aux_dot=aux_dot,
        u=u,
        u_dot=u_dot,
        kinematics=kin,
    )


def multipliers(system: System, dyn: Dynamics) -> Float[Array, " m"]:
    """Lagrange multipliers ``lambda = S^T T^T (Q - M v_dot)`` (thesis after eq. 5.61).

    Convention: ``T^T M v_dot + (Phi_q B T)^T lambda = T^T Q``. The generalised constraint
    force on the body of a joint's second point is ``+(d Phi / d x)^T lambda``, on the
    first point's body ``-(d Phi / d x)^T lambda``: for a link, ``lambda`` is its tension
    (N, positive pulls the two points together); for a spherical joint, ``lambda`` is the
    force (N, global axes) on the second point's body.
    """
    del system
    return dyn.multipliers


def check_rank(system: System, params: SystemParams, q, t=0.0, inputs: Inputs | None = None, tol=1e-9) -> None:
    """Raise :class:`RedundantConstraintError` naming the joints or velocities at fault when
    ``[Phi_q B T; P]`` loses rank at ``q`` (Python-level check on concrete values)."""
    q = jnp.asarray(q, jnp.float64)
    u, u_dot = input_state(system, inputs, jnp.asarray(t, q.dtype), q)
    phi_y = np.asarray(_jacobians(system, params, q, u, u_dot)[3])
    names_c, names_y = system.constraint_names, system.y_names
    if phi_y.shape[0] > 0:
        u, s, _ = np.linalg.svd(phi_y)
        scale = max(float(s[0]), 1.0)
        if s[-1] < tol * scale or len(s) < phi_y.shape[0]:
            null = u[:, -1]
            bad = [names_c[k] for k in np.flatnonzero(np.abs(null) > 0.1 * np.abs(null).max())]
            raise RedundantConstraintError(
                f"constraints are redundant (Phi_q B T rank {int(np.sum(s > tol * scale))} < "
                f"{phi_y.shape[0]} equations); dependent equations: {bad}"
            )
    a = np.concatenate([phi_y, np.eye(system.n_y)[list(system.independent)]])
    _, s, vt = np.linalg.svd(a)
    scale = max(float(s[0]), 1.0)
    if s[-1] < tol * scale:
        null = vt[-1]
        moving = [names_y[k] for k in np.flatnonzero(np.abs(null) > 0.1 * np.abs(null).max())]
        chosen = [names_y[k] for k in system.independent]
        raise RedundantConstraintError(
            f"independent velocities {chosen} are dependent at this configuration: the joint "
            f"velocities {moving} can move with all of them held at zero; declare another set"
        )


def check_mass_matrix(system: System, params: SystemParams, q, t=0.0, inputs: Inputs | None = None, tol=1e-12):
    """Raise :class:`SingularMassMatrixError` when the reduced mass matrix ``R^T T^T M T R``
    at ``q`` is singular or indefinite, naming the independent velocities involved."""
    check_rank(system, params, q, t, inputs)
    q = jnp.asarray(q, jnp.float64)
    proj = projection(system, params, q, t, inputs)
    tr = proj.T @ proj.R
    m_red = np.asarray(tr.T @ mass_matrix(system, params, q) @ tr)
    w, vecs = np.linalg.eigh(m_red)
    if w[0] <= tol * max(abs(w[-1]), 1.0):
        names = [system.y_names[system.independent[k]] for k in np.flatnonzero(np.abs(vecs[:, 0]) > 0.1)]
        raise SingularMassMatrixError(
            f"reduced mass matrix is singular (smallest eigenvalue {w[0]:.3e}); the independent "
            f"velocities {names} carry no inertia: give the bodies they move mass or inertia"
        )
