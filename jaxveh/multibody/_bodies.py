"""Body parameter pytrees: rigid bodies (eqs. 5.22-5.36) and modal flexible bodies (5.37-5.45).

Velocities of a body are expressed in its own moving frame: ``v = [u, omega, p_dot]`` with
``u`` the velocity of the body reference point and ``omega`` the angular velocity, both in
body axes (eq. 5.31), and ``p_dot`` the modal velocities of a flexible body.
"""

import abc
from typing import Any

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._core import float_field
from ._rotations import skew


class FlexOptions(eqx.Module):
    """Simplifications of the equations of motion (thesis section 7.6, Table 7.2); static flags.

    Flexible bodies (section 7.6.1):

    - ``constant_mass``: use the mass matrix of the undeformed body, ``M(p) = M(0)``;
    - ``neglect_gyroscopic``: drop the ``Gr`` / ``Ge`` terms of eq. (5.45), i.e. the terms
      bilinear in the angular and the modal velocities of the rotational and elastic rows;
    - ``neglect_com_shift``: drop the deformation shift of the centre of mass ``c1 = Ct p / m``.

    Coordinate reduction (section 7.6.2):

    - ``neglect_sc``: drop ``S c``, the constraint-acceleration term of eq. (5.58)
      (Table 7.2's "neglect vector c"): ``y_dot = R z_dot``;
    - ``neglect_sb``: drop ``S b`` of eq. (5.55), ``y = R z``: a rheonomic input (the rack)
      then moves the dependent coordinates only through the position correction after each
      step, as in the thesis.
    """

    constant_mass: bool = eqx.field(static=True, default=False)
    neglect_gyroscopic: bool = eqx.field(static=True, default=False)
    neglect_com_shift: bool = eqx.field(static=True, default=False)
    neglect_sc: bool = eqx.field(static=True, default=False)
    neglect_sb: bool = eqx.field(static=True, default=False)


class AbstractBody(eqx.Module):
    """A body of the library: its mass matrix in body-frame velocities ``[u, omega, p_dot]``,
    gravity, elastic forces and potential energies (what eqs. 5.25-5.45 need of it)."""

    @property
    @abc.abstractmethod
    def n_modes(self) -> int:
        """Number of modal coordinates (0 for a rigid body)."""

    @abc.abstractmethod
    def mass_matrix(self, p, options: FlexOptions):
        """Body mass matrix (6 + n_modes square) at modal coordinates ``p``."""

    @abc.abstractmethod
    def gravity(self, g_body, p, options: FlexOptions):
        """Generalised gravity force for gravity ``g_body`` in body axes (m/s^2)."""

    @abc.abstractmethod
    def elastic(self, p, p_dot):
        """Elastic and damping generalised forces on the modal coordinates."""

    @abc.abstractmethod
    def potential_gravity(self, r, a, p, g):
        """Gravitational potential energy (J) at origin ``r``, rotation ``a``."""

    @abc.abstractmethod
    def potential_elastic(self, p):
        """Strain energy (J)."""


class RigidBody(AbstractBody):
    """A rigid body: mass (kg), inertia tensor about its c.g. in body axes (kg m^2, products
    of inertia included), and the c.g. position in the body frame (m; zero for a centroidal
    reference point, the thesis's usual choice)."""

    mass: Float[Array, ""] = float_field()
    inertia: Float[Array, "3 3"] = float_field()
    cg: Float[Array, "3"] = float_field(default=(0.0, 0.0, 0.0))

    @property
    def n_modes(self) -> int:
        return 0

    def mass_matrix(self, p, options: FlexOptions) -> Float[Array, "6 6"]:
        """Constant body mass matrix about the reference point (eq. 5.25)."""
        del p, options
        m, c = self.mass, self.cg
        ct = skew(c)
        j_ref = self.inertia + m * (ct.T @ ct)
        eye = jnp.eye(3, dtype=m.dtype)
        return jnp.block([[m * eye, -m * ct], [m * ct, j_ref]])

    def gravity(self, g_body, p, options: FlexOptions) -> Float[Array, "6"]:
        """Generalised gravity force ``[m g; c x m g]`` with ``g_body`` in body axes (m/s^2)."""
        del p, options
        f = self.mass * g_body
        return jnp.concatenate([f, jnp.cross(self.cg, f)])

    def elastic(self, p, p_dot) -> Float[Array, "0"]:
        """Elastic and damping forces: none for a rigid body."""
        del p_dot
        return jnp.zeros((0,), p.dtype)

    def potential_gravity(self, r, a, p, g):
        """Gravitational potential energy (J): ``-m g . (r + A c)``."""
        del p
        return -self.mass * jnp.dot(g, r + a @ self.cg)

    def potential_elastic(self, p):
        return jnp.zeros((), p.dtype)


class FlexibleBody(AbstractBody):
    """A flexible body in a floating frame with modal coordinates ``p`` (section 5.4.2).

    ``modal`` is a modal body from the FE module (:class:`jaxveh.fe.ModalBody`: invariants
    ``mass, c0, J0, Ct, Cr0, C4, C5, Me`` of eqs. 5.38-5.42 in body axes, modal stiffness
    with its per-mode multiplier ``stiffness_scale``, damping ``alpha Me + beta K +
    diag(2 zeta_i omega_i)`` with modal damping ratios ``zeta`` (default 0.025, thesis
    section 7.3), mode shapes at named points). ``coupling`` (0..1) scales the mode shapes at the body's points
    (thesis Fig. 7.7). The mass matrix is assembled here from the invariants (eq. 5.37).
    """

    modal: Any
    coupling: Float[Array, ""] = float_field(default=1.0)

    @property
    def n_modes(self) -> int:
        return self.modal.n_modes

    def mass_matrix(self, p, options: FlexOptions) -> Float[Array, "6+nm 6+nm"]:
        """Mass matrix of eq. (5.37) at modal coordinates ``p`` (first order in ``p``), from
        the FE module's one implementation of the invariants' formulas."""
        p = jnp.zeros_like(p) if options.constant_mass else p
        return self.modal.mass_matrix(p, neglect_c=options.neglect_com_shift)

    def _com_moment(self, p):
        """``m c(p) = m c0 + Ct p`` (kg m, body axes)."""
        inv = self.modal.invariants
        return inv.mass * inv.c0 + inv.Ct @ p

    def gravity(self, g_body, p, options: FlexOptions):
        """Generalised gravity force of eq. (5.43) with ``g_body`` in body axes (m/s^2)."""
        return self.modal.gravity_forces(p, g_body, neglect_c=options.neglect_com_shift)

    def elastic(self, p, p_dot):
        """Elastic and damping generalised forces ``-(K p + D p_dot)`` (eq. 5.44)."""
        return self.modal.elastic_forces(p, p_dot)

    def potential_gravity(self, r, a, p, g):
        """Gravitational potential energy (J): ``-g . (m r + A (m c0 + Ct p))``."""
        return -jnp.dot(g, self.modal.invariants.mass * r + a @ self._com_moment(p))

    def potential_elastic(self, p):
        """Strain energy ``p^T K p / 2`` (J)."""
        return 0.5 * p @ (self.modal.stiffness_matrix() @ p)
