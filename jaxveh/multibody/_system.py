"""Builder API (thesis Table 5.1) and the immutable system: static topology + parameter pytree.

``SystemBuilder`` collects bodies, points, joints, inputs and the independent velocities;
``build()`` returns ``(system, params)``: ``system`` (:class:`System`) holds only static
Python structure (names, parents, joint kinds, counts) and ``params``
(:class:`SystemParams`) every number as a float64 leaf, so any of them can be
differentiated or vmapped.

Coordinates ``q`` (thesis eq. 5.1): a *free* body has absolute reference-point coordinates
``[x, y, z, a1, a2, a3, p...]`` (global position of the frame origin in m, three rotation
angles in rad applied in the order of its sequence, modal coordinates). A body attached to
its parent by a *tree revolute joint* (e.g. a wheel spinning on its upright, section 6.1.2)
has ``[theta, p...]``: its frame sits at ``offset`` in the parent frame and is the parent
frame rotated by ``theta`` about ``axis``.

Joint velocities ``y`` (eq. 5.47): for a free body the velocity relative to a frame rigidly
attached to its parent, in its own axes, ``[u_x, u_y, u_z, w_x, w_y, w_z, p_dot...]``
(relative to ground when it has no parent); for a tree revolute joint ``[theta_dot,
p_dot...]``. Body velocities ``v = T y`` (eq. 5.49).
"""

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import GRAVITY, ParameterError, check_range, float_field, is_concrete
from ._bodies import FlexibleBody, FlexOptions, RigidBody
from ._rotations import SEQUENCES

GROUND = "ground"
FREE = "free"
REVOLUTE = "revolute"
JOINT_SIZES = {"spherical": 3, "link": 1, "revolute": 5}


class FreeJoint(eqx.Module):
    """A body with six absolute reference-point coordinates (no numeric parameters)."""


class TreeRevolute(eqx.Module):
    """Tree revolute joint: child frame origin at ``offset`` (m, parent axes), rotation about
    the unit ``axis`` (parent axes, equal to child axes)."""

    offset: Float[Array, "3"] = float_field()
    axis: Float[Array, "3"] = float_field()


class Point(eqx.Module):
    """A point on a body: undeformed position (m, body axes), translational mode shapes at the
    point (3 x nm, m per unit modal coordinate; empty for rigid bodies), rotational mode
    shapes (3 x nm, rad per unit modal coordinate: the small rotation of the material at the
    point, body axes) and the body-axes direction along which a rheonomic input moves it (m
    per unit input; zero if none)."""

    position: Float[Array, "3"] = float_field()
    shapes: Float[Array, "3 nm"] = float_field()
    input_direction: Float[Array, "3"] = float_field()
    rotation_shapes: Float[Array, "3 nm"] = float_field()


class Spherical(eqx.Module):
    """Spherical joint ``x_P - x_Q = 0`` (eq. 5.15); ``components`` is static (in System)."""


class Link(eqx.Module):
    """Link (distance) joint of length ``length`` (m), eq. (5.16)."""

    length: Float[Array, ""] = float_field()


class Revolute(eqx.Module):
    """Revolute joint (eq. 5.17): ``axis_i`` on the first point's body, ``axis_j`` on the
    second's (unit vectors in the respective body axes)."""

    axis_i: Float[Array, "3"] = float_field()
    axis_j: Float[Array, "3"] = float_field()


class SystemParams(eqx.Module):
    """Every number of a multibody system: bodies, tree joints, points, joints, gravity (m/s^2)."""

    bodies: tuple
    tree: tuple
    points: tuple
    joints: tuple
    gravity: Float[Array, "3"] = float_field()


class System(eqx.Module):
    """Static topology of a multibody system (hashable; no arrays)."""

    body_names: tuple[str, ...] = eqx.field(static=True)
    parent: tuple[int, ...] = eqx.field(static=True)
    tree_kind: tuple[str, ...] = eqx.field(static=True)
    sequence: tuple[str, ...] = eqx.field(static=True)
    n_modes: tuple[int, ...] = eqx.field(static=True)
    point_names: tuple[str, ...] = eqx.field(static=True)
    point_body: tuple[int, ...] = eqx.field(static=True)
    point_input: tuple[int, ...] = eqx.field(static=True)
    joint_names: tuple[str, ...] = eqx.field(static=True)
    joint_kind: tuple[str, ...] = eqx.field(static=True)
    joint_points: tuple[tuple[int, int], ...] = eqx.field(static=True)
    joint_components: tuple[tuple[int, ...], ...] = eqx.field(static=True)
    input_names: tuple[str, ...] = eqx.field(static=True)
    independent: tuple[int, ...] = eqx.field(static=True)
    options: FlexOptions = eqx.field(static=True, default=FlexOptions())

    # ---- sizes and offsets (plain Python, evaluated at trace time) ----
    @property
    def n_bodies(self) -> int:
        return len(self.body_names)

    def q_size(self, i: int) -> int:
        return (6 if self.tree_kind[i] == FREE else 1) + self.n_modes[i]

    def v_size(self, i: int) -> int:
        return 6 + self.n_modes[i]

    def _offsets(self, size) -> tuple[int, ...]:
        return tuple(int(x) for x in np.cumsum([0] + [size(i) for i in range(self.n_bodies)]))

    @property
    def q_offsets(self) -> tuple[int, ...]:
        return self._offsets(self.q_size)

    @property
    def v_offsets(self) -> tuple[int, ...]:
        return self._offsets(self.v_size)

    @property
    def n_q(self) -> int:
        return self.q_offsets[-1]

    @property
    def n_v(self) -> int:
        return self.v_offsets[-1]

    @property
    def n_y(self) -> int:
        return self.n_q

    @property
    def n_constraints(self) -> int:
        return sum(len(c) for c in self.joint_components)

    @property
    def n_dof(self) -> int:
        return len(self.independent)

    @property
    def n_inputs(self) -> int:
        return len(self.input_names)

    @property
    def q_names(self) -> tuple[str, ...]:
        """``body.coordinate`` names of ``q``."""
        return tuple(f"{b}.{c}" for i, b in enumerate(self.body_names) for c in _q_labels(self, i))

    @property
    def y_names(self) -> tuple[str, ...]:
        """``body.velocity`` names of ``y``."""
        return tuple(f"{b}.{c}" for i, b in enumerate(self.body_names) for c in _y_labels(self, i))

    @property
    def constraint_names(self) -> tuple[str, ...]:
        """``joint[equation]`` names of the rows of ``Phi``."""
        out = []
        for name, kind, comps in zip(self.joint_names, self.joint_kind, self.joint_components):
            if kind == "link":
                out.append(f"{name}[length]")
            elif kind == "spherical":
                out.extend(f"{name}[{'xyz'[c]}]" for c in comps)
            else:
                out.extend([f"{name}[x]", f"{name}[y]", f"{name}[z]", f"{name}[n2.n1]", f"{name}[n3.n1]"])
        return tuple(out)

    def constraint_rows(self, joint: str) -> slice:
        """Rows of ``Phi`` (and of the multipliers) belonging to ``joint``."""
        k = self.joint_names.index(joint)
        start = sum(len(c) for c in self.joint_components[:k])
        return slice(start, start + len(self.joint_components[k]))

    def q_index(self, body: str, coordinate: str) -> int:
        """Index in ``q`` of ``coordinate`` of ``body`` (names as in :attr:`q_names`)."""
        return _lookup(self.q_names, f"{body}.{coordinate}", "coordinate")

    def y_index(self, body: str, velocity: str) -> int:
        """Index in ``y`` of ``velocity`` of ``body`` (names as in :attr:`y_names`)."""
        return _lookup(self.y_names, f"{body}.{velocity}", "velocity")

    def point_index(self, name: str) -> int:
        """Index of the point ``name``; ``ValueError`` listing the points if there is none."""
        return _lookup(self.point_names, name, "point")

    def with_options(self, options: FlexOptions) -> "System":
        """The same system with other flexible-body simplifications (Table 7.2)."""
        return dataclasses.replace(self, options=options)


def _lookup(names: tuple[str, ...], name: str, kind: str) -> int:
    if name not in names:
        raise ValueError(f"unknown {kind} {name!r}; the system has: {', '.join(names)}")
    return names.index(name)


def _q_labels(system: System, i: int) -> list[str]:
    modes = [f"p{k}" for k in range(system.n_modes[i])]
    if system.tree_kind[i] == FREE:
        return ["x", "y", "z"] + [f"rot{k}_{a}" for k, a in enumerate(system.sequence[i])] + modes
    return ["theta"] + modes


def _y_labels(system: System, i: int) -> list[str]:
    modes = [f"p{k}_dot" for k in range(system.n_modes[i])]
    if system.tree_kind[i] == FREE:
        return ["ux", "uy", "uz", "wx", "wy", "wz"] + modes
    return ["theta_dot"] + modes


def _unit(v, what: str):
    v = np.asarray(v, dtype=np.float64)
    n = float(np.linalg.norm(v))
    if v.shape != (3,) or not n > 0.0:
        raise ParameterError(f"{what} must be a non-zero 3-vector, got {v.tolist()}")
    return v / n


class SystemBuilder:
    """Describe a multibody system step by step (thesis Table 5.1), then :meth:`build` it.

    Example (thesis section 5.7)::

        b = SystemBuilder(gravity=(0.0, 0.0, -GRAVITY))
        b.add_rigid_body("B1", mass=m1, inertia=np.diag([J1, J1, J1]))
        b.add_point("P0", "ground", (0, 0, 0)); b.add_point("P1", "B1", (0, 0, a1))
        b.add_revolute("C1", "P0", "P1", axis_i=(1, 0, 0), axis_j=(1, 0, 0))
        b.add_independent("B1", "wx")
        system, params = b.build()
    """

    def __init__(self, gravity=(0.0, 0.0, -GRAVITY), options: FlexOptions = FlexOptions()):
        self._gravity = gravity
        self._options = options
        self._bodies: list[tuple] = []  # (name, params, parent, kind, sequence, tree params)
        self._points: list[tuple] = []  # (name, body index, Point, input index)
        self._joints: list[tuple] = []  # (name, kind, (i, j), components, params)
        self._inputs: list[str] = []
        self._independent: list[tuple[str, str]] = []

    # ---- bodies -------------------------------------------------------------------
    def _body_index(self, name: str) -> int:
        if name == GROUND:
            return -1
        names = [b[0] for b in self._bodies]
        if name not in names:
            raise ValueError(f"unknown body {name!r}; defined bodies: {names + [GROUND]}")
        return names.index(name)

    def _add_body(self, name, body, parent, rotation, revolute):
        if name == GROUND or name in [b[0] for b in self._bodies]:
            raise ValueError(f"body name {name!r} is reserved or already used")
        if rotation not in SEQUENCES:
            raise ValueError(f"body {name!r}: rotation sequence {rotation!r} not in {SEQUENCES}")
        parent_index = -1 if parent is None else self._body_index(parent)
        if revolute is None:
            kind, tree = FREE, FreeJoint()
        else:
            if parent_index < 0 and parent is None:
                raise ValueError(f"body {name!r}: a tree revolute joint needs a parent body (or 'ground')")
            offset, axis = revolute
            kind, tree = REVOLUTE, TreeRevolute(offset=offset, axis=_unit(axis, f"body {name!r} revolute axis"))
        self._bodies.append((name, body, parent_index, kind, rotation, tree))

    def add_rigid_body(self, name, mass, inertia, cg=(0.0, 0.0, 0.0), parent=None, rotation="zyx", revolute=None):
        """``definerigidbody``: mass (kg, >= 0: a body may carry rotary inertia only, as the
        wheels whose mass is lumped in the upright), inertia about the c.g. (3 x 3, kg m^2,
        body axes), c.g. in the body frame (m). ``parent`` (a body defined earlier or ``"ground"``) sets
        the recursion of eq. (5.47); ``revolute=(offset, axis)`` attaches the body to its
        parent by a tree revolute joint instead of six free coordinates."""
        inertia = np.asarray(inertia, dtype=np.float64)
        if not float(mass) >= 0.0:
            raise ParameterError(f"body {name!r}: mass = {float(mass):g} kg must be >= 0")
        if inertia.shape != (3, 3) or not np.allclose(inertia, inertia.T):
            raise ParameterError(f"body {name!r}: inertia must be a symmetric 3 x 3 matrix")
        if np.min(np.linalg.eigvalsh(inertia)) < 0.0:
            raise ParameterError(f"body {name!r}: inertia must be positive semi-definite")
        self._add_body(name, RigidBody(mass=mass, inertia=inertia, cg=cg), parent, rotation, revolute)

    def add_flexible_body(self, name, modal, coupling=1.0, parent=None, rotation="zyx", revolute=None):
        """``defineflexbody``: a modal body from the FE module (:class:`jaxveh.fe.ModalBody`)
        whose frame is its floating reference frame; ``coupling`` (0..1) scales the mode
        shapes at its points. Add its points with :meth:`add_modal_point`."""
        if not float(modal.mass) > 0.0:
            raise ParameterError(f"body {name!r}: mass must be > 0")
        if not np.all(np.asarray(modal.stiffness_scale) > 0.0):
            raise ParameterError(f"body {name!r}: stiffness_scale must be > 0 (a multiplier of every modal stiffness)")
        if not 0.0 <= float(coupling) <= 1.0:
            raise ParameterError(f"body {name!r}: coupling = {float(coupling):g} must be in [0, 1]")
        self._add_body(name, FlexibleBody(modal=modal, coupling=coupling), parent, rotation, revolute)

    def add_modal_point(self, name, body, modal_point, input=None, input_direction=(0.0, 0.0, 0.0)):
        """A point of a flexible body at the modal body's named point ``modal_point``:
        undeformed position and translational mode shapes taken from the FE data."""
        bi = self._body_index(body)
        modal = self._bodies[bi][1].modal if bi >= 0 else None
        if modal is None or not hasattr(modal, "point_index"):
            raise ValueError(f"point {name!r}: body {body!r} is not a flexible body")
        k = modal.point_index(modal_point)
        self.add_point(
            name,
            body,
            modal.point_xyz[k],
            modal.point_phi_translation[k],
            input,
            input_direction,
            rotation_shapes=modal.point_phi_rotation[k],
        )

    # ---- points, inputs -----------------------------------------------------------
    def add_input(self, name: str) -> None:
        """Declare a rheonomic input (e.g. the steering-rack travel, m)."""
        self._inputs.append(name)

    def add_point(
        self, name, body, position, shapes=None, input=None, input_direction=(0.0, 0.0, 0.0), rotation_shapes=None
    ):
        """``definepoint``: a point at ``position`` (m, body axes) on ``body`` (or ``"ground"``).

        ``shapes`` (3 x nm): the body's translational mode shapes at the point (flexible body).
        ``rotation_shapes`` (3 x nm, rad): its rotational mode shapes there; they turn the
        axes of revolute joints and the torques of force elements at the point (zero when
        omitted: a point that carries no moment).
        ``input``: name of a rheonomic input that moves the point by
        ``input_value * input_direction`` in body axes (the steering rack moving point M).
        """
        if name in [p[0] for p in self._points]:
            raise ValueError(f"point name {name!r} already used")
        bi = self._body_index(body)
        nm = 0 if bi < 0 else self._bodies[bi][1].n_modes
        shapes = np.zeros((3, nm)) if shapes is None else np.asarray(shapes, dtype=np.float64)
        if shapes.shape != (3, nm):
            raise ValueError(f"point {name!r}: shapes must be 3 x {nm} for body {body!r}, got {shapes.shape}")
        rot = np.zeros((3, nm)) if rotation_shapes is None else np.asarray(rotation_shapes, dtype=np.float64)
        if rot.shape != (3, nm):
            raise ValueError(f"point {name!r}: rotation_shapes must be 3 x {nm} for body {body!r}, got {rot.shape}")
        position = np.asarray(position, dtype=np.float64)
        if position.shape != (3,) or not np.all(np.isfinite(position)):
            raise ParameterError(f"point {name!r}: position must be a finite 3-vector (m), got {position.tolist()}")
        if input is not None and input not in self._inputs:
            raise ValueError(f"point {name!r}: unknown input {input!r}; declare it with add_input first")
        ii = -1 if input is None else self._inputs.index(input)
        point = Point(position=position, shapes=shapes, input_direction=input_direction, rotation_shapes=rot)
        self._points.append((name, bi, point, ii))

    # ---- joints -------------------------------------------------------------------
    def _point_pair(self, jname, p, q):
        names = [pt[0] for pt in self._points]
        for x in (p, q):
            if x not in names:
                raise ValueError(f"joint {jname!r}: unknown point {x!r}")
        i, j = names.index(p), names.index(q)
        if self._points[i][1] == self._points[j][1]:
            raise ValueError(f"joint {jname!r}: points {p!r} and {q!r} lie on the same body")
        return i, j

    def _add_joint(self, name, kind, p, q, components, params):
        if name in [j[0] for j in self._joints]:
            raise ValueError(f"joint name {name!r} already used")
        self._joints.append((name, kind, self._point_pair(name, p, q), components, params))

    def add_spherical(self, name, p, q, components="xyz"):
        """``definesphj``: points ``p`` and ``q`` coincide; ``components`` selects the global
        components imposed (e.g. ``"yz"`` for a pin of a planar mechanism in the y-z plane)."""
        comps = tuple(sorted({"xyz".index(c) for c in components}))
        self._add_joint(name, "spherical", p, q, comps, Spherical())

    def add_link(self, name, p, q, length):
        """``definelinkj``: massless rigid link of ``length`` (m) between points ``p`` and ``q``."""
        if not float(length) > 0.0:
            raise ParameterError(f"link {name!r}: length = {float(length):g} m must be > 0")
        self._add_joint(name, "link", p, q, (0,), Link(length=length))

    def add_revolute(self, name, p, q, axis_i, axis_j=None):
        """``definerevj``: ``p`` and ``q`` coincide and ``axis_i`` (on p's body) stays parallel
        to ``axis_j`` (on q's body; default the same components)."""
        ai = _unit(axis_i, f"revolute {name!r} axis_i")
        aj = ai if axis_j is None else _unit(axis_j, f"revolute {name!r} axis_j")
        self._add_joint(name, "revolute", p, q, (0, 1, 2, 3, 4), Revolute(axis_i=ai, axis_j=aj))

    def add_independent(self, body, velocity):
        """``defineindv``: declare the joint velocity ``velocity`` of ``body`` independent."""
        self._independent.append((body, velocity))

    # ---- build ----------------------------------------------------------------------
    def build(self) -> tuple[System, SystemParams]:
        """Freeze the description into ``(system, params)``."""
        if not self._bodies:
            raise ValueError("a system needs at least one body")
        system = System(
            body_names=tuple(b[0] for b in self._bodies),
            parent=tuple(b[2] for b in self._bodies),
            tree_kind=tuple(b[3] for b in self._bodies),
            sequence=tuple(b[4] for b in self._bodies),
            n_modes=tuple(b[1].n_modes for b in self._bodies),
            point_names=tuple(p[0] for p in self._points),
            point_body=tuple(p[1] for p in self._points),
            point_input=tuple(p[3] for p in self._points),
            joint_names=tuple(j[0] for j in self._joints),
            joint_kind=tuple(j[1] for j in self._joints),
            joint_points=tuple(j[2] for j in self._joints),
            joint_components=tuple(j[3] for j in self._joints),
            input_names=tuple(self._inputs),
            independent=(),
            options=self._options,
        )
        indep = []
        for body, vel in self._independent:
            name = f"{body}.{vel}"
            if name not in system.y_names:
                raise ValueError(f"independent velocity {name!r} does not exist; joint velocities: {system.y_names}")
            indep.append(system.y_names.index(name))
        if len(set(indep)) != len(indep):
            raise ValueError("an independent velocity was declared twice")
        n_dof = system.n_y - system.n_constraints
        if len(indep) != n_dof:
            raise ValueError(
                f"{len(indep)} independent velocities declared, but {system.n_y} joint velocities minus "
                f"{system.n_constraints} constraint equations leave {n_dof}; if the mechanism really has "
                f"{len(indep)} degrees of freedom, {len(indep) - n_dof} constraint equation(s) are redundant "
                "(remove them, or impose fewer spherical components)"
            )
        system = dataclasses.replace(system, independent=tuple(indep))
        params = SystemParams(
            bodies=tuple(b[1] for b in self._bodies),
            tree=tuple(b[5] for b in self._bodies),
            points=tuple(p[2] for p in self._points),
            joints=tuple(j[4] for j in self._joints),
            gravity=self._gravity,
        )
        return system, params


#: Smallest inertia eigenvalue accepted, relative to the largest (round-off of a PSD tensor).
INERTIA_PSD_RTOL = 1e-12


def _check_inertia(name: str, inertia):
    """A body's inertia must be symmetric positive semi-definite (kg m^2)."""
    xp = np if is_concrete(inertia) else jnp  # concrete: NumPy, no eager JAX operation
    inertia_xp = xp.asarray(inertia)
    w = xp.linalg.eigvalsh(0.5 * (inertia_xp + inertia_xp.T))
    smallest = w[0] / xp.maximum(xp.abs(w[-1]), 1.0)
    check_range(f"{name} inertia (smallest eigenvalue / largest)", smallest, low=-INERTIA_PSD_RTOL)
    return check_range(f"{name} inertia", inertia, low=None)


def checked_params(system: System, params: SystemParams) -> SystemParams:
    """``params`` with every number a user (or an optimiser) may change checked: masses
    >= 0 kg, inertias symmetric positive semi-definite, couplings in [0, 1], link lengths
    > 0 m, finite point positions and gravity. Concrete values raise
    :class:`~jaxveh.ParameterError` naming the body, joint or point; traced values fail at
    run time through ``eqx.error_if``. Called once by :func:`simulate`, :func:`assemble`
    and :func:`linearise` (not inside the vector field)."""
    bodies = []
    for name, body in zip(system.body_names, params.bodies):
        if isinstance(body, RigidBody):
            body = eqx.tree_at(
                lambda b: (b.mass, b.inertia),
                body,
                (check_range(f"body {name!r} mass (kg)", body.mass, low=0.0),
                 _check_inertia(f"body {name!r}", body.inertia)),
            )
        else:
            body = eqx.tree_at(
                lambda b: b.coupling, body, check_range(f"body {name!r} coupling", body.coupling, low=0.0, high=1.0)
            )
        bodies.append(body)
    joints = []
    for name, kind, joint in zip(system.joint_names, system.joint_kind, params.joints):
        if kind == "link":
            length = check_range(f"link {name!r} length (m)", joint.length, low=0.0, low_open=True)
            joint = eqx.tree_at(lambda j: j.length, joint, length)
        joints.append(joint)
    points = tuple(
        eqx.tree_at(lambda p: p.position, pt, check_range(f"point {name!r} position (m)", pt.position))
        for name, pt in zip(system.point_names, params.points)
    )
    gravity = check_range("gravity (m/s^2)", params.gravity)
    return eqx.tree_at(
        lambda p: (p.bodies, p.joints, p.points, p.gravity), params, (tuple(bodies), tuple(joints), points, gravity)
    )
