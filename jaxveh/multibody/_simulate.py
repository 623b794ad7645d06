"""Assembly (Newton-Raphson position solve) and a Diffrax simulation wrapper.

State of the ODE: ``(q, z)``, dependent coordinates and independent velocities; the vector
field is eq. (5.61) with ``q_dot = B T (R z + S b)``.
"""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._dynamics import energy
from ._errors import AssemblyError
from ._projection import Inputs, _dependent, _jacobians, dynamics, input_values, projection, solve_s
from ._kinematics import body_poses, body_velocities, constraints, qdot_from_velocities
from ._system import System, SystemParams

#: Default gain (1/s) of the velocity-level drift stabilisation ``Phi_dot = -kappa Phi``.
DEFAULT_KAPPA = 20.0
#: Assembly is accepted when every constraint residual is below this (m or rad).
ASSEMBLY_TOL = 1e-10


def assemble(
    system: System,
    params: SystemParams,
    q_guess,
    fixed: tuple[int, ...] = (),
    t=0.0,
    inputs: Inputs | None = None,
    iterations: int = 20,
    throw: bool = True,
):
    """Solve ``Phi(q, t) = 0`` by Newton-Raphson from ``q_guess`` holding ``q[fixed]``.

    A fixed number of (minimum-norm) Newton steps, so the result is differentiable in
    ``params`` and ``q_guess``. With ``throw`` and concrete values, an
    :class:`AssemblyError` names the worst constraint and its residual.
    Returns ``q``.
    """
    q_guess = jnp.asarray(q_guess, jnp.float64)
    t = jnp.asarray(t, q_guess.dtype)
    free = np.setdiff1d(np.arange(system.n_q), np.asarray(fixed, dtype=int))
    u = input_values(system, inputs, t, q_guess.dtype)

    def residual(qf):
        return constraints(system, params, q_guess.at[free].set(qf), u)

    def step(_, qf):
        r, jac = residual(qf), jax.jacfwd(residual)(qf)
        dq = jnp.linalg.lstsq(jac, r)[0]
        return qf - dq

    qf = jax.lax.fori_loop(0, iterations, step, q_guess[free])
    q = q_guess.at[free].set(qf)
    if throw and not isinstance(q, jax.core.Tracer):
        r = np.abs(np.asarray(constraints(system, params, q, u)))
        if r.size and (not np.all(np.isfinite(r)) or r.max() > ASSEMBLY_TOL):
            k = int(np.nanargmax(np.where(np.isfinite(r), r, np.inf)))
            raise AssemblyError(
                f"cannot assemble: constraint {system.constraint_names[k]} residual {r[k]:.3e} after "
                f"{iterations} Newton iterations (tolerance {ASSEMBLY_TOL:g}); check the geometry, "
                "link lengths and the initial guess"
            )
    return q


#: ``simulate`` refuses initial coordinates whose constraint residual exceeds this (m or rad).
INITIAL_RESIDUAL_TOL = 1e-8


def _check_assembled(system, params, q0, t0, inputs):
    """Raise (concrete values) or flag at run time (traced) an unassembled ``q0``."""
    if system.n_constraints == 0:
        return q0
    phi = jnp.abs(constraints(system, params, q0, input_values(system, inputs, jnp.asarray(t0, q0.dtype), q0.dtype)))
    if not isinstance(phi, jax.core.Tracer):
        r = np.asarray(phi)
        if not np.all(r <= INITIAL_RESIDUAL_TOL):
            k = int(np.argmax(np.where(np.isfinite(r), r, np.inf)))
            raise AssemblyError(
                f"initial configuration is not assembled: constraint {system.constraint_names[k]} residual "
                f"{r[k]:.3e} > {INITIAL_RESIDUAL_TOL:g}; call assemble() first"
            )
        return q0
    return eqx.error_if(
        q0, jnp.max(phi) > INITIAL_RESIDUAL_TOL, "initial configuration is not assembled; call assemble() first"
    )


def independent_velocities(system: System, y) -> Float[Array, " ndof"]:
    """``z = P y`` (eq. 5.52)."""
    return jnp.asarray(y)[jnp.asarray(system.independent)]


def joint_velocities(system: System, params: SystemParams, q, z, t=0.0, inputs=None, kappa=0.0):
    """``y = R z + S b`` (eq. 5.55)."""
    proj = projection(system, params, q, t, inputs, kappa)
    return proj.R @ z + proj.Sb


def project_coordinates(system: System, params: SystemParams, q, t, inputs=None, iterations: int = 2):
    """Newton projection of ``q`` onto ``Phi(q, t) = 0`` in the dependent joint directions:
    ``q <- q + B T dy`` with ``dy = -S Phi`` (independent velocities held), i.e. Newton's
    method with the Jacobian ``Phi_q B T`` the projection already factorises. A few
    iterations from a nearby point reach round-off."""
    if system.n_constraints == 0:
        return q
    t = jnp.asarray(t, q.dtype)

    def step(_, qq):
        phi, _, _, phi_y = _jacobians(system, params, qq, t, inputs)
        lu = jax.scipy.linalg.lu_factor(phi_y[:, jnp.asarray(_dependent(system), dtype=int)])
        dy = solve_s(system, lu, -phi)
        poses = body_poses(system, params, qq)
        vs = body_velocities(system, params, qq, dy, poses)
        return qq + qdot_from_velocities(system, params, qq, dy, vs, poses)

    return jax.lax.fori_loop(0, iterations, step, q)


class ProjectedSolver(diffrax.AbstractAdaptiveSolver, diffrax.AbstractWrappedSolver):
    """Wraps a Diffrax solver and projects ``q`` onto the constraint manifold after every
    step (Newton-Raphson position correction, thesis section 5.5.3, step 3 of the list in
    section 5.6). ``z`` needs no correction: ``y = R z + S b`` is recomputed from it at the
    corrected ``q``, so the velocity constraints hold exactly. One Newton iteration per step
    suffices: the step starts on the manifold, the residual after a step is of the order of
    the local error, and Newton squares it."""

    solver: diffrax.AbstractSolver
    system: System = eqx.field(static=True)
    iterations: int = eqx.field(static=True, default=1)

    @property
    def term_structure(self):
        return self.solver.term_structure

    @property
    def interpolation_cls(self):
        return self.solver.interpolation_cls

    def order(self, terms):
        return self.solver.order(terms)

    def error_order(self, terms):
        return self.solver.error_order(terms)

    def init(self, terms, t0, t1, y0, args):
        return self.solver.init(terms, t0, t1, y0, args)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        y1, y_error, dense_info, solver_state, result = self.solver.step(
            terms, t0, t1, y0, args, solver_state, made_jump
        )
        params, inputs = args[0], args[1]
        q1 = project_coordinates(self.system, params, y1[0], t1, inputs, self.iterations)
        y1 = (q1, y1[1])
        if isinstance(dense_info, dict) and "y1" in dense_info:
            dense_info = {**dense_info, "y1": y1}
        return y1, y_error, dense_info, solver_state, result

    def func(self, terms, t0, y0, args):
        return self.solver.func(terms, t0, y0, args)


class Simulation(eqx.Module):
    """Result of :func:`simulate`: saved times (s), ``q``, ``z``, joint velocities ``y``,
    ``residual`` (max |Phi| per saved time, m or rad), ``max_residual`` over the run,
    ``energy`` (total mechanical energy per saved time, J, without applied forces' work),
    and the Diffrax statistics."""

    ts: Float[Array, " nt"]
    q: Float[Array, "nt nq"]
    z: Float[Array, "nt ndof"]
    y: Float[Array, "nt ny"]
    residual: Float[Array, " nt"]
    max_residual: Float[Array, ""]
    energy: Float[Array, " nt"]
    stats: dict


def vector_field(system: System, kappa=DEFAULT_KAPPA):
    """Diffrax-ready vector field ``f(t, (q, z), (params, inputs, external, args))``."""

    def f(t, state, args):
        params, inputs, external, ext_args = args
        q, z = state
        dyn = dynamics(system, params, q, z, t, inputs, external, ext_args, kappa)
        return dyn.q_dot, dyn.z_dot

    return f


def simulate(
    system: System,
    params: SystemParams,
    q0,
    z0,
    t0: float,
    t1: float,
    ts=None,
    *,
    inputs: Inputs | None = None,
    external=None,
    args=None,
    solver=None,
    rtol: float = 1e-9,
    atol: float = 1e-11,
    dt0: float | None = None,
    max_steps: int = 100_000,
    kappa=DEFAULT_KAPPA,
    adjoint=None,
    project: bool = True,
    throw: bool = True,
) -> Simulation:
    """Integrate eq. (5.61) from ``(q0, z0)`` with Diffrax and report the constraint residual.

    ``q0`` must be assembled (see :func:`assemble`). ``solver`` defaults to ``Tsit5``,
    adaptive steps with a PID controller at ``rtol`` / ``atol``. Drift control: the
    velocity-level stabilisation ``Phi_dot = -kappa Phi`` inside the vector field and, with
    ``project``, a Newton projection of ``q`` after every step (:class:`ProjectedSolver`);
    the steps then land on ``ts`` and the saved ``q`` get the same projection (the
    Runge-Kutta dense output does not pass through the corrected step end). ``ts`` are the save times
    (default 101 points). The wrapper is pure: ``jax.grad`` and ``jax.vmap`` go through it.
    """
    q0, z0 = jnp.asarray(q0, jnp.float64), jnp.asarray(z0, jnp.float64)
    ts = jnp.linspace(t0, t1, 101) if ts is None else jnp.asarray(ts, jnp.float64)
    q0 = _check_assembled(system, params, q0, t0, inputs)
    solver = diffrax.Tsit5() if solver is None else solver
    if project and system.n_constraints:
        solver = ProjectedSolver(solver, system)
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(vector_field(system, kappa)),
        solver,
        t0=t0,
        t1=t1,
        dt0=dt0,
        y0=(q0, z0),
        args=(params, inputs, external, args),
        saveat=diffrax.SaveAt(ts=ts),
        stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol, step_ts=ts if project else None),
        max_steps=max_steps,
        adjoint=diffrax.RecursiveCheckpointAdjoint() if adjoint is None else adjoint,
        throw=throw,
    )
    qs, zs = sol.ys
    if project and system.n_constraints:
        qs = jax.vmap(lambda t, q: project_coordinates(system, params, q, t, inputs))(sol.ts, qs)

    def per_time(t, q, z):
        proj = projection(system, params, q, t, inputs, kappa)
        y = proj.R @ z + proj.Sb
        res = jnp.max(jnp.abs(proj.phi)) if system.n_constraints else jnp.zeros((), q.dtype)
        return y, res, energy(system, params, q, y)["total"]

    ys, res, en = jax.vmap(per_time)(sol.ts, qs, zs)
    return Simulation(
        ts=sol.ts,
        q=qs,
        z=zs,
        y=ys,
        residual=res,
        max_residual=jnp.max(res),
        energy=en,
        stats={k: sol.stats[k] for k in ("num_steps", "num_accepted_steps", "num_rejected_steps")},
    )
