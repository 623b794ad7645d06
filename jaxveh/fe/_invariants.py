"""Floating-frame modal invariants (thesis section 5.4.2, eqs. 5.37-5.45) and the
:class:`ModalBody` pytree consumed by the flexible multibody library.

Frames and notation. All vectors are in the **body reference frame** (the floating frame
the modes are measured in). Node ``k`` of the lumped-mass FE model has undeformed position
``x0_k`` (m), mass ``m_k`` (kg) and inertia tensor ``J_k`` about the node (kg m²), and mode
``l`` gives it translation ``Ψt_kl`` (m per unit modal coordinate) and small rotation
``Ψr_kl`` (rad per unit modal coordinate). With modal coordinates ``p`` the node sits at
``x_k = x0_k + Σ_l Ψt_kl p_l``. ``ã`` is the skew matrix with ``ã b = a × b``.

Invariants (lumped masses, first order in ``p`` as in the thesis). Each node is a small
rigid mass distribution that moves with the node's translation *and rotation*: a mass
point at offset ``s`` from node ``k`` is displaced by ``Ψt_k p + (Ψr_k p) × s``. The
thesis's volume integrals over these distributions are the translational sums of eqs.
5.38-5.42 plus rotary-inertia terms (``θ_kl = Ψr_kl``, ``S_k = ½ tr(J_k) I − J_k``, the
second moment ``Σ m s sᵀ`` of the node's distribution):

* ``mass`` m = Σ m_k; ``c0`` = Σ m_k x0_k / m (eq. 5.38); ``c1 = Ct / m`` so
  ``c(p) = c0 + c1 p``.
* ``J0`` = Σ J_k + m_k x̃0_kᵀ x̃0_k (eq. 5.39), inertia about the body origin.
* ``C4[l]`` = Σ m_k x̃0_k Ψ̃t_kl + J_k θ̃_kl − (S_k θ_kl)~ (3×3 per mode);
  ``J1(p) = −Σ_l (C4_l + C4_lᵀ) p_l``, whose rotary part ``Σ θ̃ J_k − J_k θ̃`` is the
  nodal inertia tensors rotated with their nodes.
* ``Ct`` = Σ m_k Ψt_k (3×N, eq. 5.40).
* ``Cr0`` = Σ m_k x̃0_k Ψt_k + J_k Ψr_k (3×N); ``C5[l]`` = Σ m_k Ψ̃t_kl Ψt_k +
  (θ̃_kl J_k − (S_k θ_kl)~) Ψr_k (3×N per mode); ``Cr1(p) = Σ_l C5_l p_l`` (eq. 5.41).
* ``Me`` = Σ Ψt_kᵀ m_k Ψt_k + Ψr_kᵀ J_k Ψr_k (N×N, eq. 5.42).

The thesis prints C4 and C5 with the translational sums only; the rotary terms make the
invariants those of the lumped mass matrix it uses, including its nodal rotary inertia
(tests compare them with explicit point clouds of the same mass, first and second
moments, and ``M(0)`` with ``½ vᵀ M_FE v`` of the assembled FE mass matrix).

Equations of motion (velocities ``z = [v, ω, ṗ]``: body-frame velocity of the origin
(m/s), body-frame angular velocity (rad/s), modal velocities) read
``M(p) ż = h_ω + h_g + h_e + Q``, with :meth:`ModalBody.mass_matrix` (eq. 5.37),
:meth:`ModalBody.gravity_forces` (5.43), :meth:`ModalBody.elastic_forces` (5.44) and
:meth:`ModalBody.quadratic_velocity_forces` (5.45). The latter follows from Lagrange's
equations in quasi-velocities for ``T = ½ zᵀ M(p) z``:

* ``Gr_l(p) = −(C4_l + C4_lᵀ) − skew(Cr_l(p))`` (3×3), rotational row ``Σ_l ṗ_l Gr_l ω``;
* ``Ge_l`` (N×3), ``(Ge_l)_j = C5_l[:, j]ᵀ − C5_j[:, l]ᵀ``, elastic row ``Σ_l ṗ_l Ge_l ω``;
* ``Oe(ω) ω = [ωᵀ C4_j ω]_j`` (centrifugal stiffening-free first-order term).

Eq. 5.45 as printed omits the term ``Σ_l ṗ_l C5_l ṗ`` of the rotational row (quadratic in
modal velocities); it is included here so the equations are the exact Lagrange equations
of ``T``; :meth:`ModalBody.quadratic_velocity_forces` documents each term.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import ParameterError, as_float, float_field, is_concrete
from ._validate import check_interval, check_nonnegative, check_positive


def skew(a: Float[Array, "3"]) -> Float[Array, "3 3"]:
    """Skew-symmetric matrix ``ã`` with ``ã b = a × b``."""
    z = jnp.zeros_like(a[0])
    return jnp.stack(
        [jnp.stack([z, -a[2], a[1]]), jnp.stack([a[2], z, -a[0]]), jnp.stack([-a[1], a[0], z])]
    )


class ModalInvariants(eqx.Module):
    """Volume integrals (here nodal sums) of a lumped-mass flexible body, body frame, SI.

    Attributes:
        mass: total mass m (kg).
        c0: undeformed centre of mass (m), shape (3,).
        J0: undeformed inertia tensor about the body origin (kg m²), (3, 3).
        Ct: translational coupling Σ m_k Ψt_k (kg), (3, N).
        Cr0: rotational coupling Σ m_k x̃0_k Ψt_k + J_k Ψr_k (kg m), (3, N).
        C4: Σ_k m_k x̃0_k Ψ̃t_kl + J_k θ̃_kl − (S_k θ_kl)~ for each mode l (kg m),
            (N, 3, 3) (module docstring).
        C5: Σ_k m_k Ψ̃t_kl Ψt_k + (θ̃_kl J_k − (S_k θ_kl)~) Ψr_k for each mode l (kg),
            (N, 3, N).
        Me: modal mass matrix (kg), (N, N); the identity for mass-normalised modes.
    """

    mass: Float[Array, ""] = float_field()
    c0: Float[Array, "3"] = float_field()
    J0: Float[Array, "3 3"] = float_field()
    Ct: Float[Array, "3 N"] = float_field()
    Cr0: Float[Array, "3 N"] = float_field()
    C4: Float[Array, "N 3 3"] = float_field()
    C5: Float[Array, "N 3 N"] = float_field()
    Me: Float[Array, "N N"] = float_field()

    @property
    def n_modes(self) -> int:
        return self.Ct.shape[1]

    @property
    def c1(self) -> Float[Array, "3 N"]:
        """Jacobian of the centre of mass w.r.t. the modal coordinates (m), eq. 5.38."""
        return self.Ct / self.mass


def modal_invariants(
    node_xyz: Float[Array, "n 3"],
    node_mass: Float[Array, " n"],
    node_inertia: Float[Array, "n 3 3"],
    phi_translation: Float[Array, "n 3 N"],
    phi_rotation: Float[Array, "n 3 N"],
) -> ModalInvariants:
    """Invariants of eqs. 5.38-5.42 from lumped nodal masses and inertias.

    Each node is a small rigid mass distribution (mass ``m_k``, inertia ``J_k`` about the
    node, centroid at the node) that moves with the node: a mass point at offset ``s``
    is displaced by ``Ψt_k p + (Ψr_k p) × s``. The thesis's volume integrals taken over
    these distributions give the translational nodal sums of the module docstring plus
    the rotary-inertia terms (``θ = Ψr_kl``, ``S_k = ½ tr(J_k) I − J_k = Σ m s sᵀ``):

    * ``J0``, ``Cr0`` and ``Me`` gain ``J_k``, ``J_k Ψr_k`` and ``Ψr_kᵀ J_k Ψr_k``;
    * ``C4_l`` gains ``J_k θ̃ − (S_k θ)~``, so ``J1`` gains ``θ̃ J_k − J_k θ̃`` (the
      node's inertia tensor rotated by θ);
    * ``C5_l`` gains ``(θ̃ J_k − (S_k θ)~) Ψr_k``.

    Args:
        node_xyz: undeformed node positions in the body frame (m).
        node_mass: nodal masses (kg).
        node_inertia: nodal inertia tensors about the node, body axes (kg m²).
        phi_translation: nodal translations per unit modal coordinate (m).
        phi_rotation: nodal rotations per unit modal coordinate (rad).
    """
    mass = jnp.sum(node_mass)
    c0 = jnp.einsum("k,ki->i", node_mass, node_xyz) / mass
    xt = jax.vmap(skew)(node_xyz)  # (n, 3, 3)
    J0 = jnp.sum(node_inertia, axis=0) + jnp.einsum("k,kji,kjl->il", node_mass, xt, xt)
    Ct = jnp.einsum("k,kil->il", node_mass, phi_translation)
    Cr0 = jnp.einsum("k,kij,kjl->il", node_mass, xt, phi_translation) + jnp.einsum(
        "kij,kjl->il", node_inertia, phi_rotation
    )
    # Ψ̃t_kl and Ψ̃r_kl for every node and mode: (n, N, 3, 3)
    skew_nodes_modes = jax.vmap(jax.vmap(skew, in_axes=1), in_axes=0)
    pt = skew_nodes_modes(phi_translation)
    rt = skew_nodes_modes(phi_rotation)
    # second moments S_k = Σ m s sᵀ of the nodal distributions; (S_k θ_kl)~: (n, N, 3, 3)
    trace = jnp.trace(node_inertia, axis1=1, axis2=2)
    second = 0.5 * trace[:, None, None] * jnp.eye(3)[None, :, :] - node_inertia
    st = skew_nodes_modes(jnp.einsum("kij,kjl->kil", second, phi_rotation))
    C4 = jnp.einsum("k,kij,klja->lia", node_mass, xt, pt) + jnp.einsum(
        "kij,klja->lia", node_inertia, rt
    ) - jnp.sum(st, axis=0)
    C5 = (
        jnp.einsum("k,klij,kjm->lim", node_mass, pt, phi_translation)
        + jnp.einsum("klij,kja,kam->lim", rt, node_inertia, phi_rotation)
        - jnp.einsum("klij,kjm->lim", st, phi_rotation)
    )
    Me = jnp.einsum("k,kil,kim->lm", node_mass, phi_translation, phi_translation) + jnp.einsum(
        "kil,kij,kjm->lm", phi_rotation, node_inertia, phi_rotation
    )
    return ModalInvariants(mass, c0, J0, Ct, Cr0, C4, C5, Me)


#: Default modal damping ratio of every chassis mode: "the relative eigenvalues lie on the
#: line corresponding to ζ = 0.025" (thesis section 7.3, uncoupled chassis modes).
DEFAULT_DAMPING_RATIO = 0.025


def damping_parameters(
    n_modes: int, damping_ratio=None, alpha=None, beta=None
) -> tuple[Float[Array, " N"], Float[Array, ""], Float[Array, ""]]:
    """``(damping_ratio (N,), alpha, beta)`` float64 arrays from a user's choice.

    * nothing given: modal damping ``ζ = DEFAULT_DAMPING_RATIO`` on every mode;
    * ``alpha`` and/or ``beta`` only: Rayleigh damping ``α Me + β K`` alone (ζ = 0; the
      missing coefficient is 0);
    * ``damping_ratio`` (scalar or one per mode), optionally with ``alpha``/``beta``: both,
      ``De = α Me + β K + diag(2 ζ_i sqrt(K_ii Me_ii))``.

    Raises ``ParameterError`` for ζ outside [0, 1), α or β < 0, or a ζ vector whose length
    is not ``n_modes``. Returns arrays, so new values never retrace a jitted caller.
    """
    rayleigh = alpha is not None or beta is not None
    if damping_ratio is None:
        damping_ratio = 0.0 if rayleigh else DEFAULT_DAMPING_RATIO
    zeta = as_float(damping_ratio)
    if zeta.ndim == 0:
        zeta = jnp.full((n_modes,), zeta)
    if zeta.shape != (n_modes,):
        raise ParameterError(
            f"damping_ratio must be a scalar or have one value per mode ({n_modes}), got shape {zeta.shape}"
        )
    zeta = check_damping_ratio(zeta)
    alpha = check_nonnegative("alpha (Rayleigh mass-proportional damping, 1/s)", 0.0 if alpha is None else alpha)
    beta = check_nonnegative("beta (Rayleigh stiffness-proportional damping, s)", 0.0 if beta is None else beta)
    return zeta, alpha, beta


def check_damping_ratio(zeta):
    """Modal damping ratios in [0, 1) (under-critical); see :func:`check_interval`."""
    return check_interval("damping_ratio", zeta, low=0.0, high=1.0, high_open=True, what="modal damping ratio")


def modal_damping_ratios(
    frequencies_hz: Float[Array, " N"], damping_ratio=None, alpha=None, beta=None
) -> Float[Array, " N"]:
    """Damping ratio of each uncoupled mode (natural frequency ``f_i`` in Hz) for the
    damping chosen as in :func:`damping_parameters`:
    ``ζ_i = ζ_modal,i + α / (2 ω_i) + β ω_i / 2`` with ``ω_i = 2π f_i``. Values >= 1 are
    over-critical (real eigenvalues)."""
    f = check_positive("frequencies_hz", frequencies_hz, "Hz")
    zeta, a, b = damping_parameters(f.shape[0], damping_ratio, alpha, beta)
    w = 2.0 * jnp.pi * f
    return zeta + a / (2.0 * w) + 0.5 * b * w


def _safe_sqrt(x):
    pos = x > 0.0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, x, 1.0)), 0.0)


class ModalBody(eqx.Module):
    """A modally reduced flexible body for the multibody library (section 5.4.2).

    Attributes:
        invariants: :class:`ModalInvariants` (body frame, SI).
        Ke: modal stiffness matrix (N/m per unit modal coordinate²), (N, N); diagonal
            ``(2π f)²`` for mass-normalised free-free modes.
        alpha: Rayleigh mass-proportional damping coefficient α (1/s), >= 0.
        beta: Rayleigh stiffness-proportional damping coefficient β (s), >= 0.
        damping_ratio: modal damping ratio ζ_i of every mode, (N,), in [0, 1); the
            default of :func:`modal_body` and :func:`~jaxveh.fe.frame_modal_body` is 0.025
            (thesis section 7.3) with α = β = 0.
        stiffness_scale: per-mode stiffness multiplier µ (Figs. 7.2d, 7.10d), (N,) > 0.
        point_names: names of the points where mode shapes are kept (static).
        point_xyz: undeformed positions of those points, body frame (m), (P, 3).
        point_phi_translation: mode-shape translations at the points (m), (P, 3, N).
        point_phi_rotation: mode-shape rotations at the points (rad), (P, 3, N).

    Damping (eq. 5.44): ``De = α Me + β K + diag(2 ζ_i sqrt(K_ii Me_ii))`` with the
    µ-scaled stiffness ``K``; for mass-normalised modes the last term is ``2 ζ_i ω_i`` and
    ``ω_i`` follows µ. Concrete values are checked on construction (``ParameterError``);
    the methods check them again at run time, so traced values (an optimiser's) raise an
    error instead of giving NaN or a silently negative stiffness.
    """

    invariants: ModalInvariants
    Ke: Float[Array, "N N"] = float_field()
    alpha: Float[Array, ""] = float_field()
    beta: Float[Array, ""] = float_field()
    damping_ratio: Float[Array, " N"] = float_field()
    stiffness_scale: Float[Array, " N"] = float_field()
    point_names: tuple[str, ...] = eqx.field(static=True)
    point_xyz: Float[Array, "P 3"] = float_field()
    point_phi_translation: Float[Array, "P 3 N"] = float_field()
    point_phi_rotation: Float[Array, "P 3 N"] = float_field()

    def __check_init__(self):
        n = self.Ke.shape[0]
        shapes = {
            "Ke": (self.Ke.shape, (n, n)),
            "alpha": (self.alpha.shape, ()),
            "beta": (self.beta.shape, ()),
            "damping_ratio": (self.damping_ratio.shape, (n,)),
            "stiffness_scale": (self.stiffness_scale.shape, (n,)),
            "invariants.Me": (self.invariants.Me.shape, (n, n)),
        }
        for name, (got, want) in shapes.items():
            if got != want:
                raise ParameterError(f"ModalBody.{name} must have shape {want} for {n} modes, got {got}")
        if len(self.point_names) != self.point_xyz.shape[0]:
            raise ParameterError("ModalBody.point_names and point_xyz must have the same length")
        # concrete values are checked now; traced ones at run time by the methods
        for check, value in (
            (self._scale, self.stiffness_scale),
            (self._alpha, self.alpha),
            (self._beta, self.beta),
            (self._zeta, self.damping_ratio),
        ):
            if is_concrete(value):
                check()

    @property
    def n_modes(self) -> int:
        return self.Ke.shape[0]

    @property
    def mass(self) -> Float[Array, ""]:
        return self.invariants.mass

    def point_index(self, name: str) -> int:
        """Index of a named point; ``ParameterError`` listing the known names if absent."""
        if name not in self.point_names:
            raise ParameterError(f"modal body has no point {name!r}; known points: {list(self.point_names)}")
        return self.point_names.index(name)

    # --- checked values -----------------------------------------------------------------
    def _scale(self):
        return check_positive("ModalBody.stiffness_scale", self.stiffness_scale, "stiffness multiplier µ")

    def _alpha(self):
        return check_nonnegative("ModalBody.alpha", self.alpha, "Rayleigh mass-proportional damping, 1/s")

    def _beta(self):
        return check_nonnegative("ModalBody.beta", self.beta, "Rayleigh stiffness-proportional damping, s")

    def _zeta(self):
        return check_interval(
            "ModalBody.damping_ratio", self.damping_ratio, low=0.0, high=1.0, high_open=True, what="modal damping ratio"
        )

    # --- stiffness and damping (eq. 5.44) ---------------------------------------------
    def stiffness_matrix(self) -> Float[Array, "N N"]:
        """``Ke`` scaled by µ: ``K_ij = Ke_ij sqrt(µ_i µ_j)`` (= µ_i Ke_ii for diagonal Ke)."""
        s = jnp.sqrt(self._scale())
        return self.Ke * s[:, None] * s[None, :]

    def _modal_damping(self, K: Float[Array, "N N"]) -> Float[Array, " N"]:
        """``c_i = 2 ζ_i sqrt(K_ii Me_ii)`` (= 2 ζ_i ω_i for mass-normalised modes)."""
        return 2.0 * self._zeta() * _safe_sqrt(jnp.diagonal(K) * jnp.diagonal(self.invariants.Me))

    def damping_matrix(self) -> Float[Array, "N N"]:
        """``De = α Me + β K + diag(2 ζ_i sqrt(K_ii Me_ii))`` with the µ-scaled stiffness."""
        K = self.stiffness_matrix()
        return self._alpha() * self.invariants.Me + self._beta() * K + jnp.diag(self._modal_damping(K))

    def damping_ratios(self) -> Float[Array, " N"]:
        """Damping ratio of every uncoupled mode, ``De_ii / (2 sqrt(K_ii Me_ii))`` (1 is
        critical): ``ζ_i + α / (2 ω_i) + β ω_i / 2`` for mass-normalised modes."""
        K = self.stiffness_matrix()
        critical = 2.0 * jnp.sqrt(jnp.diagonal(K) * jnp.diagonal(self.invariants.Me))
        return jnp.diagonal(self.damping_matrix()) / critical

    @property
    def frequencies_hz(self) -> Float[Array, " N"]:
        """Natural frequencies of the uncoupled modes (Hz), ``sqrt(K_ii / Me_ii) / 2π``
        with the µ-scaled stiffness: the FE frequencies times ``sqrt(µ)`` for the
        (diagonal) mass-normalised modes every constructor builds."""
        K = self.stiffness_matrix()
        return jnp.sqrt(jnp.diagonal(K) / jnp.diagonal(self.invariants.Me)) / (2.0 * jnp.pi)

    def elastic_forces(self, p: Float[Array, " N"], pd: Float[Array, " N"]) -> Float[Array, " N"]:
        """Elastic + damping generalised force on the modal coordinates, as a right-hand
        side: ``−(K p + De ṗ)`` (eq. 5.44 moved to the right)."""
        return -(self.stiffness_matrix() @ p + self.damping_matrix() @ pd)

    # --- configuration-dependent inertia terms (eqs. 5.38-5.42) ------------------------
    def com(self, p: Float[Array, " N"]) -> Float[Array, "3"]:
        """Centre of mass ``c = c0 + c1 p`` (m, body frame)."""
        return self.invariants.c0 + self.invariants.c1 @ p

    def inertia(self, p: Float[Array, " N"]) -> Float[Array, "3 3"]:
        """Inertia about the body origin ``J = J0 + J1(p)`` (kg m²)."""
        c4 = self.invariants.C4
        return self.invariants.J0 - jnp.einsum("lij,l->ij", c4 + jnp.swapaxes(c4, 1, 2), p)

    def Cr(self, p: Float[Array, " N"]) -> Float[Array, "3 N"]:
        """Rotation-elastic coupling ``Cr = Cr0 + Σ_l C5_l p_l`` (kg m)."""
        return self.invariants.Cr0 + jnp.einsum("lim,l->im", self.invariants.C5, p)

    def mass_matrix(self, p: Float[Array, " N"], neglect_c: bool = False) -> Float[Array, "6+N 6+N"]:
        """Mass matrix of eq. 5.37 for velocities ``[v, ω, ṗ]`` (body frame); ``neglect_c``
        (static, thesis Table 7.2) drops the deformation shift of the centre of mass."""
        inv = self.invariants
        mct = inv.mass * skew(inv.c0 if neglect_c else self.com(p))
        cr = self.Cr(p)
        top = jnp.concatenate([inv.mass * jnp.eye(3), -mct, inv.Ct], axis=1)
        mid = jnp.concatenate([mct, self.inertia(p), cr], axis=1)
        bot = jnp.concatenate([inv.Ct.T, cr.T, inv.Me], axis=1)
        return jnp.concatenate([top, mid, bot], axis=0)

    # --- gyroscopic terms (eq. 5.45) ---------------------------------------------------
    def Gr(self, p: Float[Array, " N"]) -> Float[Array, "N 3 3"]:
        """``Gr_l = −(C4_l + C4_lᵀ) − skew(Cr_l(p))`` (kg m), one 3×3 per mode."""
        c4 = self.invariants.C4
        return -(c4 + jnp.swapaxes(c4, 1, 2)) - jax.vmap(skew, in_axes=1)(self.Cr(p))

    def Ge(self) -> Float[Array, "N N 3"]:
        """``(Ge_l)_{j,:} = C5_l[:, j] − C5_j[:, l]`` (kg), one N×3 per mode l."""
        c5 = self.invariants.C5  # (l, i, j)
        return jnp.swapaxes(c5, 1, 2) - jnp.transpose(c5, (2, 0, 1))

    def Oe(self, omega: Float[Array, "3"]) -> Float[Array, " N"]:
        """``Oe(ω) ω = [ωᵀ C4_j ω]_j`` (N)."""
        return jnp.einsum("i,jik,k->j", omega, self.invariants.C4, omega)

    def quadratic_velocity_forces(
        self,
        p: Float[Array, " N"],
        v: Float[Array, "3"],
        omega: Float[Array, "3"],
        pd: Float[Array, " N"],
    ) -> Float[Array, " 6+N"]:
        """Gyroscopic and Coriolis forces ``h_ω`` (eq. 5.45) as a right-hand side.

        ``h_ω = −[ m ω̃ v + m ω̃ ω̃ c + 2 ω̃ Ct ṗ ;
                   ω̃ J ω + m c̃ ω̃ v + Σ_l ṗ_l Gr_l ω + Σ_l ṗ_l C5_l ṗ ;
                   Ctᵀ ω̃ v + Σ_l ṗ_l Ge_l ω + Oe(ω) ω ]``
        with ``v`` the body-frame velocity of the body origin (m/s) and ``ω`` the body
        angular velocity (rad/s).
        """
        inv = self.invariants
        c = self.com(p)
        wt = skew(omega)
        ht = inv.mass * (wt @ v) + inv.mass * (wt @ (wt @ c)) + 2.0 * (wt @ (inv.Ct @ pd))
        hr = (
            wt @ (self.inertia(p) @ omega)
            + inv.mass * (skew(c) @ (wt @ v))
            + jnp.einsum("l,lij,j->i", pd, self.Gr(p), omega)
            + jnp.einsum("l,lim,m->i", pd, inv.C5, pd)
        )
        he = inv.Ct.T @ (wt @ v) + jnp.einsum("l,ljk,k->j", pd, self.Ge(), omega) + self.Oe(omega)
        return -jnp.concatenate([ht, hr, he])

    def gravity_forces(
        self, p: Float[Array, " N"], g: Float[Array, "3"], neglect_c: bool = False
    ) -> Float[Array, " 6+N"]:
        """Gravity ``h_g = [m g; m c̃ g; Ctᵀ g]`` (eq. 5.43); ``g`` in body axes (m/s²);
        ``neglect_c`` as in :meth:`mass_matrix`."""
        inv = self.invariants
        c = inv.c0 if neglect_c else self.com(p)
        return jnp.concatenate([inv.mass * g, inv.mass * jnp.cross(c, g), inv.Ct.T @ g])

    # --- kinematics of named points ----------------------------------------------------
    def point_displacement(self, p: Float[Array, " N"]) -> Float[Array, "P 3"]:
        """Elastic translation of every named point (m, body frame): ``Ψt p``."""
        return jnp.einsum("pil,l->pi", self.point_phi_translation, p)

    def point_rotation(self, p: Float[Array, " N"]) -> Float[Array, "P 3"]:
        """Small elastic rotation vector of every named point (rad, body frame): ``Ψr p``."""
        return jnp.einsum("pil,l->pi", self.point_phi_rotation, p)


def modal_body(
    node_xyz: Float[Array, "n 3"],
    node_mass: Float[Array, " n"],
    node_inertia: Float[Array, "n 3 3"],
    phi_translation: Float[Array, "n 3 N"],
    phi_rotation: Float[Array, "n 3 N"],
    Ke: Float[Array, "N N"],
    point_names: tuple[str, ...],
    point_index: tuple[int, ...],
    *,
    damping_ratio=None,
    alpha=None,
    beta=None,
) -> ModalBody:
    """Assemble a :class:`ModalBody` from nodal data (body frame, SI) and modal data.

    ``point_index[i]`` is the node index of ``point_names[i]``. Damping as in
    :func:`damping_parameters`: by default ζ = 0.025 on every mode (thesis section 7.3);
    giving ``alpha``/``beta`` alone selects Rayleigh damping. µ starts at 1 for every mode.
    """
    if len(point_names) != len(point_index):
        raise ParameterError("point_names and point_index must have the same length")
    n = Ke.shape[0]
    zeta, alpha, beta = damping_parameters(n, damping_ratio, alpha, beta)
    idx = np.asarray(point_index, dtype=np.int64)
    return ModalBody(
        invariants=modal_invariants(node_xyz, node_mass, node_inertia, phi_translation, phi_rotation),
        Ke=Ke,
        alpha=alpha,
        beta=beta,
        damping_ratio=zeta,
        stiffness_scale=jnp.ones(n),
        point_names=tuple(point_names),
        point_xyz=node_xyz[idx],
        point_phi_translation=phi_translation[idx],
        point_phi_rotation=phi_rotation[idx],
    )
