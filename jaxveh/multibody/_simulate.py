"""Assembly (Newton-Raphson position solve) and a Diffrax simulation wrapper.

State of the ODE: ``(q, z)``, dependent coordinates and independent velocities; the vector
field is eq. (5.61) with ``q_dot = B T (R z + S b)``.
"""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, Float

from .._core import is_concrete
from ._dynamics import energy
from ._errors import AssemblyError
from ._forces import aux_names, aux_offsets
from ._imex import ModalImplicitPart, modal_implicit_part
from ._kinematics import (
    body_poses,
    body_velocities,
    constraints,
    marker_positions,
    qdot_from_velocities,
)
from ._projection import Inputs, _dependent, _jacobians, dynamics, input_values, projection, solve_s
from ._system import System, SystemParams, checked_params

#: Default gain (1/s) of the velocity-level drift stabilisation ``Phi_dot = -kappa Phi``.
DEFAULT_KAPPA = 20.0
#: Assembly is accepted when every constraint residual is below this (m or rad).
ASSEMBLY_TOL = 1e-10


#: Largest rotation (rad) of any body between the initial guess and the assembled
#: configuration that :func:`assemble` accepts by default. A Newton solve that turns a body
#: further has almost always left the intended assembly branch (e.g. a wheel flipped
#: through 90 deg of camber); steering an upright by a rack stays well within it.
MAX_BRANCH_ROTATION = 0.75


class AssemblyResult(eqx.Module):
    """Outcome of :func:`solve_assembly`: ``q`` (the guess wherever the solve produced
    non-finite values, so the result is NaN-free), ``residual`` (max |Phi|, m or rad),
    ``worst`` (row of the largest residual), ``rotation`` (largest body rotation from the
    guess, rad), ``flipped`` (a link reversed its direction relative to the guess), and
    ``ok`` (converged below ``ASSEMBLY_TOL`` on the guess's branch)."""

    q: Float[Array, " nq"]
    residual: Float[Array, ""]
    worst: Array
    rotation: Float[Array, ""]
    flipped: Array
    ok: Array


def _body_rotations(system, params, q):
    return jnp.stack([pose[1] for pose in body_poses(system, params, q)])


def _rotation_change(system, params, q_from, q_to):
    """Largest rotation angle (rad) of any body between two configurations."""
    a, b = _body_rotations(system, params, q_from), _body_rotations(system, params, q_to)
    cos = (jnp.einsum("kij,kij->k", a, b) - 1.0) / 2.0
    return jnp.max(jnp.arccos(jnp.clip(cos, -1.0, 1.0)))


def _links_flipped(system, params, q_from, q_to, u):
    """True when a link joint's vector turned by more than 90 deg (a reversed link)."""
    links = [k for k, kind in enumerate(system.joint_kind) if kind == "link"]
    if not links:
        return jnp.asarray(False)
    idx = np.asarray([system.joint_points[k] for k in links], dtype=int)

    def vectors(q):
        x = marker_positions(system, params, q, u)
        return x[idx[:, 0]] - x[idx[:, 1]]

    return jnp.any(jnp.sum(vectors(q_from) * vectors(q_to), axis=1) <= 0.0)


def solve_assembly(
    system: System,
    params: SystemParams,
    q_guess,
    fixed: tuple[int, ...] = (),
    t=0.0,
    inputs: Inputs | None = None,
    iterations: int = 20,
    max_rotation=MAX_BRANCH_ROTATION,
) -> AssemblyResult:
    """Solve ``Phi(q, t) = 0`` by Newton-Raphson from ``q_guess`` holding ``q[fixed]``.

    A fixed number of (minimum-norm) Newton steps, so the result is differentiable in
    ``params`` and ``q_guess`` and works under ``jit`` / ``vmap``; it never raises (see
    :func:`assemble`) but reports convergence and a jump to another assembly branch: a body
    rotated by more than ``max_rotation`` (rad) from the guess, or a link whose direction
    reversed.
    """
    q_guess = jnp.asarray(q_guess, jnp.float64)
    params = checked_params(system, params)
    t = jnp.asarray(t, q_guess.dtype)
    free = np.setdiff1d(np.arange(system.n_q), np.asarray(fixed, dtype=int))
    u = input_values(system, inputs, t, q_guess.dtype, q_guess)

    def residual(qf):
        return constraints(system, params, q_guess.at[free].set(qf), u)

    def step(_, qf):
        r, jac = residual(qf), jax.jacfwd(residual)(qf)
        dq = jnp.linalg.lstsq(jac, r)[0]
        return qf - dq

    q = q_guess.at[free].set(jax.lax.fori_loop(0, iterations, step, q_guess[free]))
    finite = jnp.all(jnp.isfinite(q))
    q = jnp.where(finite, q, q_guess)
    r = jnp.abs(constraints(system, params, q, u))
    residual_max = jnp.max(r, initial=0.0)
    worst = jnp.argmax(r) if r.size else jnp.asarray(0)
    rotation = _rotation_change(system, params, q_guess, q)
    flipped = _links_flipped(system, params, q_guess, q, u)
    ok = finite & (residual_max <= ASSEMBLY_TOL) & (rotation <= max_rotation) & ~flipped
    return AssemblyResult(q=q, residual=residual_max, worst=worst, rotation=rotation, flipped=flipped, ok=ok)


def assembly_message(system: System, result: AssemblyResult, max_rotation=MAX_BRANCH_ROTATION) -> str:
    """Why an assembly failed, naming the constraint and its gap or the branch jump."""
    if float(result.residual) > ASSEMBLY_TOL:
        name = system.constraint_names[int(result.worst)]
        return (
            f"cannot assemble: constraint {name} residual (gap) {float(result.residual):.3e} m or rad ("
            f"tolerance {ASSEMBLY_TOL:g}); the configuration cannot be reached: check the geometry, "
            "link lengths, the imposed motion and the initial guess"
        )
    if bool(result.flipped):
        return (
            "assembly jumped to another branch: a link reversed its direction relative to the initial guess; "
            "check the link lengths and the initial guess"
        )
    return (
        f"assembly jumped to another branch: a body rotated by {np.degrees(float(result.rotation)):.1f} deg from "
        f"the initial guess (limit {np.degrees(float(max_rotation)):.1f} deg); check the link lengths, or give a "
        "closer initial guess"
    )


def assemble(
    system: System,
    params: SystemParams,
    q_guess,
    fixed: tuple[int, ...] = (),
    t=0.0,
    inputs: Inputs | None = None,
    iterations: int = 20,
    throw: bool = True,
    max_rotation=MAX_BRANCH_ROTATION,
):
    """Assembled coordinates ``q`` by :func:`solve_assembly`.

    With ``throw`` a failure raises: :class:`AssemblyError` naming the worst constraint and
    its residual, or the branch jump, for concrete values; a run-time error
    (``eqx.error_if``) under ``jit``. ``throw=False`` returns the (NaN-free) ``q`` as it is;
    use :func:`solve_assembly` to get the flags.
    """
    result = solve_assembly(system, params, q_guess, fixed, t, inputs, iterations, max_rotation)
    if not throw:
        return result.q
    if is_concrete(result.ok):
        if not bool(result.ok):
            raise AssemblyError(assembly_message(system, result, max_rotation))
        return result.q
    return eqx.error_if(
        result.q, ~result.ok, "cannot assemble, or the assembly jumped to another branch (call solve_assembly for why)"
    )


#: ``simulate`` refuses initial coordinates whose constraint residual exceeds this (m or rad).
INITIAL_RESIDUAL_TOL = 1e-8


class State(eqx.Module):
    """State of the ODE: coordinates ``q``, independent velocities ``z`` and the force
    elements' auxiliary states ``aux`` (empty when there are none)."""

    q: Float[Array, " nq"]
    z: Float[Array, " ndof"]
    aux: Float[Array, " na"]


def _check_assembled(system, params, q0, t0, inputs, aux0):
    """Raise (concrete values) or flag at run time (traced) an unassembled ``q0``."""
    if system.n_constraints == 0:
        return q0
    u = input_values(system, inputs, jnp.asarray(t0, q0.dtype), q0.dtype, q0, aux0)
    phi = jnp.abs(constraints(system, params, q0, u))
    if is_concrete(phi):
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


def joint_velocities(system: System, params: SystemParams, q, z, t=0.0, inputs=None, kappa=0.0, aux=None):
    """``y = R z + S b`` (eq. 5.55)."""
    proj = projection(system, params, q, t, inputs, kappa, aux)
    return proj.R @ z + proj.Sb


def project_coordinates(system: System, params: SystemParams, q, t, inputs=None, iterations: int = 2, aux=None):
    """Newton projection of ``q`` onto ``Phi(q, t) = 0`` in the dependent joint directions:
    ``q <- q + B T dy`` with ``dy = -S Phi`` (independent velocities held), i.e. Newton's
    method with the Jacobian ``Phi_q B T`` the projection already factorises. A few
    iterations from a nearby point reach round-off. Touches ``q`` only."""
    if system.n_constraints == 0:
        return q
    t = jnp.asarray(t, q.dtype)
    dep = jnp.asarray(_dependent(system), dtype=int)

    def step(_, qq):
        u = input_values(system, inputs, t, qq.dtype, qq, aux)
        phi, _, _, phi_y = _jacobians(system, params, qq, u, jnp.zeros_like(u))
        dy = solve_s(system, jax.scipy.linalg.lu_factor(phi_y[:, dep]), -phi)
        poses = body_poses(system, params, qq)
        vs = body_velocities(system, params, qq, dy, poses)
        return qq + qdot_from_velocities(system, params, qq, dy, vs, poses)

    return jax.lax.fori_loop(0, iterations, step, q)


class ProjectedSolver(diffrax.AbstractAdaptiveSolver, diffrax.AbstractWrappedSolver):
    """Wraps a Diffrax solver and projects ``q`` onto the constraint manifold after every
    step (Newton-Raphson position correction, thesis section 5.5.3, step 3 of the list in
    section 5.6). ``z`` and ``aux`` need no correction: ``y = R z + S b`` is recomputed from
    ``z`` at the corrected ``q``, so the velocity constraints hold exactly. One Newton
    iteration per step suffices: the step starts on the manifold, the residual after a step
    is of the order of the local error, and Newton squares it.

    ``freeze_steps = k > 0`` (a simplification in the spirit of thesis section 7.6.2): the
    projection matrices (``T``, ``Phi_q B T``, ``R`` and the LU factors that give ``S``) are
    computed at the start of every k-th attempted step and held for all stages of the next
    k steps; the vector field gets them as a fifth element of ``args``. ``0``: recomputed at
    every evaluation (exact)."""

    solver: diffrax.AbstractSolver
    system: System = eqx.field(static=True)
    iterations: int = eqx.field(static=True, default=1)
    freeze_steps: int = eqx.field(static=True, default=0)

    @property
    def term_structure(self):
        return self.solver.term_structure

    @property
    def interpolation_cls(self):
        return self.solver.interpolation_cls

    @property
    def root_finder(self):  # diffrax sees through wrapped solvers: implicit inner solvers
        return self.solver.root_finder

    @property
    def root_find_max_steps(self):
        return self.solver.root_find_max_steps

    def order(self, terms):
        return self.solver.order(terms)

    def error_order(self, terms):
        return self.solver.error_order(terms)

    def _projection(self, args, t, y):
        params, inputs = args[0], args[1]
        return projection(self.system, params, y.q, t, inputs, 0.0, y.aux)

    def init(self, terms, t0, t1, y0, args):
        if not self.freeze_steps:
            return self.solver.init(terms, t0, t1, y0, args)
        frozen = self._projection(args, t0, y0)
        inner = self.solver.init(terms, t0, t1, y0, (*args, frozen))
        return inner, frozen, jnp.zeros((), jnp.int32)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        if self.freeze_steps:
            inner, frozen, count = solver_state
            frozen = jax.lax.cond(
                count % self.freeze_steps == 0, lambda: self._projection(args, t0, y0), lambda: frozen
            )
            y1, y_error, dense_info, inner, result = self.solver.step(
                terms, t0, t1, y0, (*args, frozen), inner, made_jump
            )
            solver_state = (inner, frozen, count + 1)
        else:
            y1, y_error, dense_info, solver_state, result = self.solver.step(
                terms, t0, t1, y0, args, solver_state, made_jump
            )
        params, inputs = args[0], args[1]
        q1 = project_coordinates(self.system, params, y1.q, t1, inputs, self.iterations, y1.aux)
        y1 = State(q1, y1.z, y1.aux)
        if isinstance(dense_info, dict) and "y1" in dense_info:
            dense_info = {**dense_info, "y1": y1}
        return y1, y_error, dense_info, solver_state, result

    def func(self, terms, t0, y0, args):
        return self.solver.func(terms, t0, y0, args)


class Simulation(eqx.Module):
    """Result of :func:`simulate`.

    ``ts`` saved times (s); ``q``, ``z``, ``aux`` and joint velocities ``y`` there;
    ``residual`` (max |Phi| per saved time, m or rad) and ``max_residual``; ``energy``
    (mechanical energy per saved time, J, without the work of applied forces); ``outputs``
    (the user's named channels, a pytree of arrays with a leading time axis; None without
    ``outputs``); ``valid`` (False at save times after the run stopped: values there hold
    the last state); ``stop_reason`` ("completed", the name of the event that fired, or the
    solver's failure message with its time; "traced" under ``jit``, where ``status`` tells:
    0 completed, 1 event, 2 solver failure); ``stop_time`` (s) and ``final`` (the state
    there, uncorrected); and the Diffrax statistics."""

    ts: Float[Array, " nt"]
    q: Float[Array, "nt nq"]
    z: Float[Array, "nt ndof"]
    aux: Float[Array, "nt na"]
    y: Float[Array, "nt ny"]
    residual: Float[Array, " nt"]
    max_residual: Float[Array, ""]
    energy: Float[Array, " nt"]
    outputs: object
    valid: Array
    stop_reason: str = eqx.field(static=True)
    stop_time: Float[Array, ""]
    status: Array
    final: State
    stats: dict


def vector_field(system: System, kappa=DEFAULT_KAPPA, elements: tuple = ()):
    """Diffrax-ready vector field ``f(t, State, (params, inputs, external, args[, frozen]))``
    (``frozen``: held projection matrices, see :class:`ProjectedSolver`)."""

    def f(t, state, args):
        params, inputs, external, ext_args, *frozen = args
        dyn = dynamics(system, params, state.q, state.z, t, inputs, external, ext_args, kappa, elements, state.aux,
                       frozen[0] if frozen else None)
        return State(dyn.q_dot, dyn.z_dot, dyn.aux_dot)

    return f


#: Newton tolerances of the implicit stages: they are linear, so Newton solves them in one
#: iteration and a second confirms. Diffrax's default, a chord method at the step
#: controller's tolerances, failed on the vehicle benchmark at rtol 1e-6 (step rejections
#: until ``max_steps``).
IMEX_NEWTON_RTOL, IMEX_NEWTON_ATOL = 1e-8, 1e-10
#: Diffrax's implicit-explicit solvers (``terms=MultiTerm(explicit, implicit)``).
IMEX_SOLVERS = (diffrax.KenCarp3, diffrax.KenCarp4, diffrax.KenCarp5, diffrax.Sil3)


def default_imex_solver():
    """``KenCarp4`` (4th order, L-stable implicit part) with a Newton root finder."""
    return diffrax.KenCarp4(root_finder=optx.Newton(rtol=IMEX_NEWTON_RTOL, atol=IMEX_NEWTON_ATOL))


class _Remainder(eqx.Module):
    """The explicit part of the IMEX split: the full vector field minus the implicit one."""

    field: object
    implicit: ModalImplicitPart

    def __call__(self, t, state, args):
        full, lin = self.field(t, state, args), self.implicit(t, state, args)
        return jax.tree.map(jnp.subtract, full, lin)


def _event(events):
    """A Diffrax event from ``{name: cond(t, state) -> bool}`` (None for no events)."""
    if not events:
        return None
    names = tuple(events)
    conds = tuple(lambda t, y, args, fn=events[n], **kw: fn(t, y) for n in names)
    return diffrax.Event(cond_fn=conds), names


def _hold_after_stop(x, valid):
    """Replace values at save times after the stop (Diffrax's inf) by the last valid one."""
    last = jnp.maximum(jnp.sum(valid) - 1, 0)
    return jnp.where(valid.reshape((-1,) + (1,) * (x.ndim - 1)), x, x[last])


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
    elements: tuple = (),
    aux0=None,
    outputs=None,
    events: dict | None = None,
    solver=None,
    rtol: float = 1e-9,
    atol: float = 1e-11,
    dt0: float | None = None,
    jump_ts=None,
    max_steps: int = 100_000,
    kappa=DEFAULT_KAPPA,
    adjoint=None,
    project: bool = True,
    implicit_modes: bool = False,
    freeze_steps: int = 0,
    progress: bool = False,
    throw: bool = True,
) -> Simulation:
    """Integrate eq. (5.61) from ``(q0, z0, aux0)`` with Diffrax and report the residual.

    ``q0`` must be assembled (see :func:`assemble`). ``elements``: force elements
    (:class:`AbstractForceElement`) with initial auxiliary states ``aux0`` (default zeros).
    ``inputs``: a function of time or an input law (closed-loop inputs read the state).
    ``outputs(t, state, dyn) -> pytree`` gives named channels, evaluated at the save times
    ``ts`` (default 101 points) on the dense output, after the position correction of the
    saved ``q``: save times never force integrator steps. ``events``: ``{name: cond(t,
    state) -> bool}``; the run stops when one becomes True and ``stop_reason`` names it.
    ``solver`` defaults to ``Tsit5``, adaptive steps with a PID controller at ``rtol`` /
    ``atol``; ``jump_ts`` (s): times where the inputs' derivatives jump, where steps end.
    Drift control: the velocity-level stabilisation ``Phi_dot = -kappa Phi`` and, with
    ``project``, a Newton projection of ``q`` after every step
    (:class:`ProjectedSolver`). ``implicit_modes``: integrate the flexible bodies' linear
    elastic and damping forces implicitly and the rest explicitly (IMEX, :mod:`._imex`);
    ``solver`` then defaults to ``KenCarp4`` with a Newton root finder and must be an IMEX
    solver. For stiff chassis modes, whose explicit step is bounded by stability (1.6-1.9x
    faster on the vehicle benchmark at rtol 1e-3). ``freeze_steps = k``: hold the projection
    matrices for k steps (see :class:`ProjectedSolver`; needs ``project``). ``progress``
    prints a text progress meter. With ``throw``
    a solver failure raises (Diffrax's message says when and why); without, the result
    says it in ``stop_reason`` and holds the last valid state. Pure: ``jax.grad`` and
    ``jax.vmap`` go through it.
    """
    q0, z0 = jnp.asarray(q0, jnp.float64), jnp.asarray(z0, jnp.float64)
    elements = tuple(elements)
    n_aux = aux_offsets(elements)[-1]
    aux0 = jnp.zeros((n_aux,)) if aux0 is None else jnp.asarray(aux0, jnp.float64)
    if aux0.shape != (n_aux,):
        raise ValueError(f"aux0 must hold {n_aux} auxiliary states {aux_names(elements)}, got shape {aux0.shape}")
    params = checked_params(system, params)
    ts = jnp.linspace(t0, t1, 101) if ts is None else jnp.asarray(ts, jnp.float64)
    q0 = _check_assembled(system, params, q0, t0, inputs, aux0)
    field = vector_field(system, kappa, elements)
    if implicit_modes:
        part = modal_implicit_part(
            system, params, q0, z0, jnp.asarray(t0, q0.dtype), inputs, external, args, elements, aux0, kappa
        )
        terms = diffrax.MultiTerm(diffrax.ODETerm(_Remainder(field, part)), diffrax.ODETerm(part))
        solver = default_imex_solver() if solver is None else solver
        if not isinstance(solver, IMEX_SOLVERS):
            raise ValueError(
                f"implicit_modes needs an IMEX solver ({', '.join(c.__name__ for c in IMEX_SOLVERS)}), "
                f"got {type(solver).__name__}"
            )
    else:
        terms = diffrax.ODETerm(field)
        solver = diffrax.Tsit5() if solver is None else solver
    if not (isinstance(freeze_steps, int) and freeze_steps >= 0):
        raise ValueError(f"freeze_steps = {freeze_steps!r} is out of range: allowed integers >= 0 (0: exact)")
    if freeze_steps and not (project and system.n_constraints):
        raise ValueError("freeze_steps needs project=True and a system with constraints (it holds R and S)")
    if project and system.n_constraints:
        solver = ProjectedSolver(solver, system, freeze_steps=freeze_steps)
    event = _event(events)
    sol = diffrax.diffeqsolve(
        terms,
        solver,
        t0=t0,
        t1=t1,
        dt0=dt0,
        y0=State(q0, z0, aux0),
        args=(params, inputs, external, args),
        saveat=diffrax.SaveAt(ts=ts, t1=True),  # t1: where the run actually ended (events)
        stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol, jump_ts=jump_ts),
        max_steps=max_steps,
        adjoint=diffrax.RecursiveCheckpointAdjoint() if adjoint is None else adjoint,
        event=None if event is None else event[0],
        progress_meter=diffrax.TextProgressMeter() if progress else diffrax.NoProgressMeter(),
        throw=throw,
    )
    # Diffrax saves [ts before the stop..., the stop (t1 or an event), inf...]
    last = jnp.sum(jnp.isfinite(sol.ts)) - 1
    end = jax.tree.map(lambda x: x[last], sol.ys)
    saved = jax.tree.map(lambda x: x[: ts.shape[0]], sol.ys)
    valid = sol.ts[: ts.shape[0]] == ts
    qs, zs, auxs = (_hold_after_stop(x, valid) for x in (saved.q, saved.z, saved.aux))
    if project and system.n_constraints:
        qs = jax.vmap(lambda t, q, a: project_coordinates(system, params, q, t, inputs, 2, a))(ts, qs, auxs)

    def per_time(t, q, z, aux):
        dyn = dynamics(system, params, q, z, t, inputs, external, args, kappa, elements, aux)
        res = jnp.max(jnp.abs(dyn.projection.phi)) if system.n_constraints else jnp.zeros((), q.dtype)
        out = None if outputs is None else outputs(t, State(q, z, aux), dyn)
        return dyn.y, res, energy(system, params, q, dyn.y)["total"], out

    ys, res, en, outs = jax.vmap(per_time)(ts, qs, zs, auxs)
    reason = _stop_reason(sol, event)
    return Simulation(
        ts=ts,
        q=qs,
        z=zs,
        aux=auxs,
        y=ys,
        residual=res,
        max_residual=jnp.max(res),
        energy=en,
        outputs=outs,
        valid=valid,
        stop_reason=reason,
        stop_time=sol.ts[last],
        final=end,
        status=_status(sol.result),
        stats={k: sol.stats[k] for k in ("num_steps", "num_accepted_steps", "num_rejected_steps")},
    )


def _status(result):
    """0 completed, 1 stopped by an event, 2 solver failure (an array, also under ``jit``)."""
    return jnp.where(
        result._value == diffrax.RESULTS.successful._value,
        0,
        jnp.where(result._value == diffrax.RESULTS.event_occurred._value, 1, 2),
    )


def _stop_reason(sol, event) -> str:
    """Why the run stopped, as text (concrete values only)."""
    if not is_concrete(sol.result._value):
        return "traced"
    if sol.result == diffrax.RESULTS.event_occurred and event is not None:
        fired = [n for n, m in zip(event[1], sol.event_mask) if bool(m)]
        return "event: " + ", ".join(fired)
    if sol.result != diffrax.RESULTS.successful:
        stop = float(np.nanmax(np.where(np.isfinite(sol.ts), sol.ts, np.nan)))
        return f"solver failed at t = {stop:.6g} s: {diffrax.RESULTS[sol.result]}"
    return "completed"
