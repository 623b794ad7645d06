"""The Magic Formula 5.2 tyre as an Equinox pytree: one float64 leaf per coefficient.

Every numeric key of an MF 5.2 / PAC2002 ``.tir`` property file is a field here, named as
in the file but in lower case (``PKY1`` -> ``pky1``). Field metadata records the ``.tir``
section, the description and whether the key is required, so :mod:`jaxveh.tyre._tir` reads
and writes files from this one definition. Units are SI (m, N, rad, s, kg) throughout.

Two ``jaxveh`` extensions, in a ``[RELAXATION_LENGTH]`` section: constant relaxation lengths
``SIGMA_KAPPA`` and ``SIGMA_ALPHA`` (Table B.4: 0.3 m), used when the file does not define
the MF 5.2 load-dependent forms (``PTX1``, ``PTY1``).
"""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._core import is_concrete
from ..params import float_field
from ._base import AbstractTyre, TyreForces
from ._checks import check_tyre, coefficient_ranges
from ._magic_formula import tyre_forces
from ._transient import relaxation_lengths
from ._vertical import effective_rolling_radius, vertical_force

#: Fit types of the MF 5.x family this model implements (MF-Tyre 5.0/5.1/5.2, PAC2002).
SUPPORTED_FITTYP: tuple[int, ...] = (5, 6, 21)

#: Relaxation-length models: constant lengths, or the MF 5.2 load-dependent forms.
RELAXATION_MODELS: tuple[str, ...] = ("constant", "mf52")


def _c(section: str, default: float, doc: str, required: bool = False):
    """A coefficient field: float64 leaf with its ``.tir`` section and description."""
    return float_field(default=default, metadata={"section": section, "doc": doc, "required": required})


_MOD, _DIM, _VER = "MODEL", "DIMENSION", "VERTICAL"
_KR, _AR, _CR, _FR = "LONG_SLIP_RANGE", "SLIP_ANGLE_RANGE", "INCLINATION_ANGLE_RANGE", "VERTICAL_FORCE_RANGE"
_SC, _LO = "SCALING_COEFFICIENTS", "LONGITUDINAL_COEFFICIENTS"
_OV, _LA = "OVERTURNING_COEFFICIENTS", "LATERAL_COEFFICIENTS"
_RO, _AL, _RL = "ROLLING_COEFFICIENTS", "ALIGNING_COEFFICIENTS", "RELAXATION_LENGTH"

Scalar = Float[Array, ""]


class MagicFormulaTyre(AbstractTyre):
    """Magic Formula 5.2 (PAC2002) coefficients, ISO-W sign convention, SI units.

    Build one with :func:`jaxveh.tyre.read_tir`, :func:`jaxveh.tyre.load_fsae_tyre`, or by
    keyword (missing coefficients take the MF-Tyre neutral default: 1 for scaling factors
    ``L*``, 0 otherwise). Every coefficient is a float64 array leaf: ``jax.grad`` with
    respect to the tyre and ``jax.vmap`` over stacked tyres work directly.

    Static fields: ``fittyp`` (the file's FITTYP), ``relaxation_model`` (``"constant"`` or
    ``"mf52"``) and ``extras`` (keys and sections of the file this model does not use,
    kept verbatim so a read/write round trip loses nothing).
    """

    # [MODEL]
    vxlow: Scalar = _c(_MOD, 1.0, "Speed below which low-speed treatment applies [m/s]")
    longvl: Scalar = _c(_MOD, 16.7, "Measurement speed [m/s]")
    # [DIMENSION]
    unloaded_radius: Scalar = _c(_DIM, 0.3, "Free tyre radius [m]", True)
    width: Scalar = _c(_DIM, 0.2, "Nominal section width [m]")
    aspect_ratio: Scalar = _c(_DIM, 0.5, "Nominal aspect ratio [-]")
    rim_radius: Scalar = _c(_DIM, 0.2, "Nominal rim radius [m]")
    rim_width: Scalar = _c(_DIM, 0.15, "Rim width [m]")
    # [VERTICAL]
    vertical_stiffness: Scalar = _c(_VER, 2.0e5, "Tyre vertical stiffness [N/m]")
    vertical_damping: Scalar = _c(_VER, 50.0, "Tyre vertical damping [Ns/m]")
    breff: Scalar = _c(_VER, 0.0, "Low load stiffness of effective rolling radius [-]")
    dreff: Scalar = _c(_VER, 0.0, "Peak value of effective rolling radius [-]")
    freff: Scalar = _c(_VER, 0.0, "High load stiffness of effective rolling radius [-]")
    fnomin: Scalar = _c(_VER, 4000.0, "Nominal wheel load [N]", True)
    # ranges
    kpumin: Scalar = _c(_KR, -1.5, "Minimum valid wheel slip [-]")
    kpumax: Scalar = _c(_KR, 1.5, "Maximum valid wheel slip [-]")
    alpmin: Scalar = _c(_AR, -1.5, "Minimum valid slip angle [rad]")
    alpmax: Scalar = _c(_AR, 1.5, "Maximum valid slip angle [rad]")
    cammin: Scalar = _c(_CR, -0.3, "Minimum valid camber angle [rad]")
    cammax: Scalar = _c(_CR, 0.3, "Maximum valid camber angle [rad]")
    fzmin: Scalar = _c(_FR, 0.0, "Minimum allowed wheel load [N]")
    fzmax: Scalar = _c(_FR, 1.0e5, "Maximum allowed wheel load [N]")
    # [SCALING_COEFFICIENTS]
    lfzo: Scalar = _c(_SC, 1.0, "Scale factor of nominal (rated) load")
    lcx: Scalar = _c(_SC, 1.0, "Scale factor of Fx shape factor")
    lmux: Scalar = _c(_SC, 1.0, "Scale factor of Fx peak friction coefficient")
    lex: Scalar = _c(_SC, 1.0, "Scale factor of Fx curvature factor")
    lkx: Scalar = _c(_SC, 1.0, "Scale factor of Fx slip stiffness")
    lhx: Scalar = _c(_SC, 1.0, "Scale factor of Fx horizontal shift")
    lvx: Scalar = _c(_SC, 1.0, "Scale factor of Fx vertical shift")
    lgax: Scalar = _c(_SC, 1.0, "Scale factor of camber for Fx")
    lcy: Scalar = _c(_SC, 1.0, "Scale factor of Fy shape factor")
    lmuy: Scalar = _c(_SC, 1.0, "Scale factor of Fy peak friction coefficient")
    ley: Scalar = _c(_SC, 1.0, "Scale factor of Fy curvature factor")
    lky: Scalar = _c(_SC, 1.0, "Scale factor of Fy cornering stiffness")
    lhy: Scalar = _c(_SC, 1.0, "Scale factor of Fy horizontal shift")
    lvy: Scalar = _c(_SC, 1.0, "Scale factor of Fy vertical shift")
    lgay: Scalar = _c(_SC, 1.0, "Scale factor of camber for Fy")
    ltr: Scalar = _c(_SC, 1.0, "Scale factor of peak of pneumatic trail")
    lres: Scalar = _c(_SC, 1.0, "Scale factor for offset of residual torque")
    lgaz: Scalar = _c(_SC, 1.0, "Scale factor of camber for Mz")
    lxal: Scalar = _c(_SC, 1.0, "Scale factor of alpha influence on Fx")
    lyka: Scalar = _c(_SC, 1.0, "Scale factor of kappa influence on Fy")
    lvyka: Scalar = _c(_SC, 1.0, "Scale factor of kappa induced Fy")
    ls: Scalar = _c(_SC, 1.0, "Scale factor of moment arm of Fx")
    lsgkp: Scalar = _c(_SC, 1.0, "Scale factor of relaxation length of Fx")
    lsgal: Scalar = _c(_SC, 1.0, "Scale factor of relaxation length of Fy")
    lgyr: Scalar = _c(_SC, 1.0, "Scale factor of gyroscopic torque")
    lmx: Scalar = _c(_SC, 1.0, "Scale factor of overturning couple")
    lvmx: Scalar = _c(_SC, 1.0, "Scale factor of Mx vertical shift")
    lmy: Scalar = _c(_SC, 1.0, "Scale factor of rolling resistance torque")
    # [LONGITUDINAL_COEFFICIENTS]
    pcx1: Scalar = _c(_LO, 1.65, "Shape factor Cfx for longitudinal force", True)
    pdx1: Scalar = _c(_LO, 1.0, "Longitudinal friction Mux at Fznom", True)
    pdx2: Scalar = _c(_LO, 0.0, "Variation of friction Mux with load")
    pdx3: Scalar = _c(_LO, 0.0, "Variation of friction Mux with camber squared")
    pex1: Scalar = _c(_LO, 0.0, "Longitudinal curvature Efx at Fznom")
    pex2: Scalar = _c(_LO, 0.0, "Variation of curvature Efx with load")
    pex3: Scalar = _c(_LO, 0.0, "Variation of curvature Efx with load squared")
    pex4: Scalar = _c(_LO, 0.0, "Factor in curvature Efx while driving")
    pkx1: Scalar = _c(_LO, 20.0, "Longitudinal slip stiffness Kfx/Fz at Fznom", True)
    pkx2: Scalar = _c(_LO, 0.0, "Variation of slip stiffness Kfx/Fz with load")
    pkx3: Scalar = _c(_LO, 0.0, "Exponent in slip stiffness Kfx/Fz with load")
    phx1: Scalar = _c(_LO, 0.0, "Horizontal shift Shx at Fznom")
    phx2: Scalar = _c(_LO, 0.0, "Variation of shift Shx with load")
    pvx1: Scalar = _c(_LO, 0.0, "Vertical shift Svx/Fz at Fznom")
    pvx2: Scalar = _c(_LO, 0.0, "Variation of shift Svx/Fz with load")
    rbx1: Scalar = _c(_LO, 0.0, "Slope factor for combined slip Fx reduction")
    rbx2: Scalar = _c(_LO, 0.0, "Variation of slope Fx reduction with kappa")
    rcx1: Scalar = _c(_LO, 0.0, "Shape factor for combined slip Fx reduction")
    rex1: Scalar = _c(_LO, 0.0, "Curvature factor of combined Fx")
    rex2: Scalar = _c(_LO, 0.0, "Curvature factor of combined Fx with load")
    rhx1: Scalar = _c(_LO, 0.0, "Shift factor for combined slip Fx reduction")
    ptx1: Scalar = _c(_LO, 0.0, "Relaxation length SigKap0/Fz at Fznom")
    ptx2: Scalar = _c(_LO, 0.0, "Variation of SigKap0/Fz with load")
    ptx3: Scalar = _c(_LO, 0.0, "Variation of SigKap0/Fz with exponent of load")
    # [OVERTURNING_COEFFICIENTS]
    qsx1: Scalar = _c(_OV, 0.0, "Lateral force induced overturning moment")
    qsx2: Scalar = _c(_OV, 0.0, "Camber induced overturning couple")
    qsx3: Scalar = _c(_OV, 0.0, "Fy induced overturning couple")
    # [LATERAL_COEFFICIENTS]
    pcy1: Scalar = _c(_LA, 1.3, "Shape factor Cfy for lateral forces", True)
    pdy1: Scalar = _c(_LA, 1.0, "Lateral friction Muy", True)
    pdy2: Scalar = _c(_LA, 0.0, "Variation of friction Muy with load")
    pdy3: Scalar = _c(_LA, 0.0, "Variation of friction Muy with squared camber")
    pey1: Scalar = _c(_LA, 0.0, "Lateral curvature Efy at Fznom")
    pey2: Scalar = _c(_LA, 0.0, "Variation of curvature Efy with load")
    pey3: Scalar = _c(_LA, 0.0, "Zero order camber dependency of curvature Efy")
    pey4: Scalar = _c(_LA, 0.0, "Variation of curvature Efy with camber")
    pky1: Scalar = _c(_LA, -20.0, "Maximum value of stiffness Kfy/Fznom", True)
    pky2: Scalar = _c(_LA, 2.0, "Load at which Kfy reaches maximum value", True)
    pky3: Scalar = _c(_LA, 0.0, "Variation of Kfy/Fznom with camber")
    phy1: Scalar = _c(_LA, 0.0, "Horizontal shift Shy at Fznom")
    phy2: Scalar = _c(_LA, 0.0, "Variation of shift Shy with load")
    phy3: Scalar = _c(_LA, 0.0, "Variation of shift Shy with camber")
    pvy1: Scalar = _c(_LA, 0.0, "Vertical shift in Svy/Fz at Fznom")
    pvy2: Scalar = _c(_LA, 0.0, "Variation of shift Svy/Fz with load")
    pvy3: Scalar = _c(_LA, 0.0, "Variation of shift Svy/Fz with camber")
    pvy4: Scalar = _c(_LA, 0.0, "Variation of shift Svy/Fz with camber and load")
    rby1: Scalar = _c(_LA, 0.0, "Slope factor for combined Fy reduction")
    rby2: Scalar = _c(_LA, 0.0, "Variation of slope Fy reduction with alpha")
    rby3: Scalar = _c(_LA, 0.0, "Shift term for alpha in slope Fy reduction")
    rcy1: Scalar = _c(_LA, 0.0, "Shape factor for combined Fy reduction")
    rey1: Scalar = _c(_LA, 0.0, "Curvature factor of combined Fy")
    rey2: Scalar = _c(_LA, 0.0, "Curvature factor of combined Fy with load")
    rhy1: Scalar = _c(_LA, 0.0, "Shift factor for combined Fy reduction")
    rhy2: Scalar = _c(_LA, 0.0, "Shift factor for combined Fy reduction with load")
    rvy1: Scalar = _c(_LA, 0.0, "Kappa induced side force Svyk/Muy*Fz at Fznom")
    rvy2: Scalar = _c(_LA, 0.0, "Variation of Svyk/Muy*Fz with load")
    rvy3: Scalar = _c(_LA, 0.0, "Variation of Svyk/Muy*Fz with camber")
    rvy4: Scalar = _c(_LA, 0.0, "Variation of Svyk/Muy*Fz with alpha")
    rvy5: Scalar = _c(_LA, 0.0, "Variation of Svyk/Muy*Fz with kappa")
    rvy6: Scalar = _c(_LA, 0.0, "Variation of Svyk/Muy*Fz with atan(kappa)")
    pty1: Scalar = _c(_LA, 0.0, "Peak value of relaxation length SigAlp0/R0")
    pty2: Scalar = _c(_LA, 0.0, "Value of Fz/Fznom where SigAlp0 is extreme")
    # [ROLLING_COEFFICIENTS]
    qsy1: Scalar = _c(_RO, 0.0, "Rolling resistance torque coefficient")
    qsy2: Scalar = _c(_RO, 0.0, "Rolling resistance torque depending on Fx")
    qsy3: Scalar = _c(_RO, 0.0, "Rolling resistance torque depending on speed")
    qsy4: Scalar = _c(_RO, 0.0, "Rolling resistance torque depending on speed^4")
    # [ALIGNING_COEFFICIENTS]
    qbz1: Scalar = _c(_AL, 10.0, "Trail slope factor for trail Bpt at Fznom", True)
    qbz2: Scalar = _c(_AL, 0.0, "Variation of slope Bpt with load")
    qbz3: Scalar = _c(_AL, 0.0, "Variation of slope Bpt with load squared")
    qbz4: Scalar = _c(_AL, 0.0, "Variation of slope Bpt with camber")
    qbz5: Scalar = _c(_AL, 0.0, "Variation of slope Bpt with absolute camber")
    qbz9: Scalar = _c(_AL, 0.0, "Slope factor Br of residual torque Mzr")
    qbz10: Scalar = _c(_AL, 0.0, "Slope factor Br of residual torque Mzr (times By Cy)")
    qcz1: Scalar = _c(_AL, 1.2, "Shape factor Cpt for pneumatic trail", True)
    qdz1: Scalar = _c(_AL, 0.1, "Peak trail Dpt'' = Dpt*(Fz/Fznom*R0)", True)
    qdz2: Scalar = _c(_AL, 0.0, "Variation of peak Dpt'' with load")
    qdz3: Scalar = _c(_AL, 0.0, "Variation of peak Dpt'' with camber")
    qdz4: Scalar = _c(_AL, 0.0, "Variation of peak Dpt'' with camber squared")
    qdz6: Scalar = _c(_AL, 0.0, "Peak residual torque Dmr'' = Dmr/(Fz*R0)")
    qdz7: Scalar = _c(_AL, 0.0, "Variation of peak factor Dmr'' with load")
    qdz8: Scalar = _c(_AL, 0.0, "Variation of peak factor Dmr'' with camber")
    qdz9: Scalar = _c(_AL, 0.0, "Variation of peak factor Dmr'' with camber and load")
    qez1: Scalar = _c(_AL, 0.0, "Trail curvature Ept at Fznom")
    qez2: Scalar = _c(_AL, 0.0, "Variation of curvature Ept with load")
    qez3: Scalar = _c(_AL, 0.0, "Variation of curvature Ept with load squared")
    qez4: Scalar = _c(_AL, 0.0, "Variation of curvature Ept with sign of Alpha-t")
    qez5: Scalar = _c(_AL, 0.0, "Variation of Ept with camber and sign Alpha-t")
    qhz1: Scalar = _c(_AL, 0.0, "Trail horizontal shift Sht at Fznom")
    qhz2: Scalar = _c(_AL, 0.0, "Variation of shift Sht with load")
    qhz3: Scalar = _c(_AL, 0.0, "Variation of shift Sht with camber")
    qhz4: Scalar = _c(_AL, 0.0, "Variation of shift Sht with camber and load")
    ssz1: Scalar = _c(_AL, 0.0, "Nominal value of s/R0: effect of Fx on Mz")
    ssz2: Scalar = _c(_AL, 0.0, "Variation of distance s/R0 with Fy/Fznom")
    ssz3: Scalar = _c(_AL, 0.0, "Variation of distance s/R0 with camber")
    ssz4: Scalar = _c(_AL, 0.0, "Variation of distance s/R0 with load and camber")
    qtz1: Scalar = _c(_AL, 0.0, "Gyration torque constant")
    mbelt: Scalar = _c(_AL, 0.0, "Belt mass of the wheel [kg]")
    # [RELAXATION_LENGTH] (jaxveh extension; Table B.4)
    sigma_kappa: Scalar = _c(_RL, 0.3, "Constant longitudinal relaxation length [m]")
    sigma_alpha: Scalar = _c(_RL, 0.3, "Constant lateral relaxation length [m]")
    # static structure
    fittyp: int = eqx.field(static=True, default=6)
    relaxation_model: str = eqx.field(static=True, default="constant")
    extras: tuple[tuple[str, str, str], ...] = eqx.field(static=True, default=())

    def __check_init__(self):
        if self.fittyp not in SUPPORTED_FITTYP:
            raise ValueError(
                f"FITTYP={self.fittyp} is not supported: this is the MF 5.2 family model, "
                f"FITTYP must be one of {SUPPORTED_FITTYP}"
            )
        if self.relaxation_model not in RELAXATION_MODELS:
            raise ValueError(f"relaxation_model must be one of {RELAXATION_MODELS}, got {self.relaxation_model!r}")
        ranges = coefficient_ranges(self.relaxation_model)
        if all(is_concrete(getattr(self, n)) for n in ranges):
            check_tyre(self)

    def forces(self, fz: ArrayLike, kappa: ArrayLike, alpha: ArrayLike, gamma: ArrayLike, vx: ArrayLike) -> TyreForces:
        """:func:`jaxveh.tyre.tyre_forces` of this tyre."""
        return tyre_forces(check_tyre(self), fz, kappa, alpha, gamma, vx)

    def relaxation_lengths(self, fz: ArrayLike, gamma: ArrayLike) -> tuple[Scalar, Scalar]:
        """:func:`jaxveh.tyre.relaxation_lengths` of this tyre [m]."""
        return relaxation_lengths(check_tyre(self), fz, gamma)

    def vertical_force(self, deflection: ArrayLike, deflection_rate: ArrayLike) -> Scalar:
        """:func:`jaxveh.tyre.vertical_force` of this tyre [N]."""
        return vertical_force(check_tyre(self), deflection, deflection_rate)

    def effective_rolling_radius(self, fz: ArrayLike) -> Scalar:
        """:func:`jaxveh.tyre.effective_rolling_radius` of this tyre [m]."""
        return effective_rolling_radius(check_tyre(self), fz)


def coefficient_fields() -> tuple[dataclasses.Field, ...]:
    """The numeric fields of :class:`MagicFormulaTyre`, in ``.tir`` order."""
    return tuple(f for f in dataclasses.fields(MagicFormulaTyre) if "section" in f.metadata)


def coefficient_names() -> tuple[str, ...]:
    """Lower-case names of all numeric coefficients."""
    return tuple(f.name for f in coefficient_fields())


def stack_tyres(tyres) -> MagicFormulaTyre:
    """Stack tyres along a new leading axis of every coefficient, for ``jax.vmap``.

    Tyres read from different files differ in their static ``extras`` (kept only for
    writing ``.tir`` files); the stacked tyre drops them. ``fittyp`` and
    ``relaxation_model`` must agree (they change the computation).

    Raises:
        ValueError: no tyres, or differing ``relaxation_model`` / ``fittyp``.
    """
    tyres = list(tyres)
    if not tyres:
        raise ValueError("stack_tyres needs at least one tyre")
    models = {(t.fittyp, t.relaxation_model) for t in tyres}
    if len(models) > 1:
        raise ValueError(f"stack_tyres: tyres differ in (fittyp, relaxation_model): {sorted(models)}")
    bare = [dataclasses.replace(t, extras=()) for t in tyres]
    return jax.tree.map(lambda *x: jnp.stack(x), *bare)


#: Coefficients that make MF 5.2 differ between left and right turns: offsets and the odd
#: terms of functions that must be even (section by section of :func:`tyre_forces`).
ASYMMETRIC_COEFFICIENTS = (
    "phy1", "phy2", "pvy1", "pvy2", "pey3",  # pure Fy: horizontal and vertical shifts, curvature asymmetry
    "rhx1", "rby3", "rvy1", "rvy2",  # combined Fx and Fy: the slip-angle shift, kappa-induced side force
    "qhz1", "qhz2", "qbz4", "qdz3", "qez4", "qdz6", "qdz7", "ssz1",  # Mz: trail shift and odd terms, offsets
    "qsx1",  # Mx offset
)


def mirror_symmetric(tyre: MagicFormulaTyre) -> MagicFormulaTyre:
    """``tyre`` with :data:`ASYMMETRIC_COEFFICIENTS` zeroed (every other one kept; stacked
    tyres too): Fy, Mz and Mx become odd and Fx, My even under ``(alpha, gamma) ->
    (-alpha, -gamma)`` at any slip ratio and load, so a car on such tyres (and with a
    symmetric chassis) answers a right turn with the mirror image of a left one. For
    symmetry checks and studies that want the tyre's mean behaviour without its ply steer and
    conicity."""
    return eqx.tree_at(lambda t: tuple(getattr(t, n) for n in ASYMMETRIC_COEFFICIENTS), tyre,
                       tuple(jnp.zeros_like(getattr(tyre, n)) for n in ASYMMETRIC_COEFFICIENTS))
