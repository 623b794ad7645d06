"""Tyres: Magic Formula 5.2 (PAC2002) in pure JAX, ``.tir`` files, relaxation, fitting.

Sign convention ISO-W (see :mod:`jaxveh.tyre._magic_formula`); the mapping to the vehicle
axes (x forward, y left, z up) is in :mod:`jaxveh.tyre._axes`. The functions that take a
tyre check its coefficients first (:func:`check_tyre`); see "Input validation" in
``docs/tyre.md``.
"""

from . import _magic_formula, _transient, _vertical
from ._axes import (
    forces_to_vehicle as forces_to_vehicle,
    inclination_angle as inclination_angle,
    slip_velocities as slip_velocities,
    velocity_to_wheel as velocity_to_wheel,
)
from ._base import AbstractTyre as AbstractTyre, TyreForces as TyreForces
from ._checks import (
    MF52_RELAXATION_COEFFICIENTS as MF52_RELAXATION_COEFFICIENTS,
    NON_NEGATIVE_COEFFICIENTS as NON_NEGATIVE_COEFFICIENTS,
    POSITIVE_COEFFICIENTS as POSITIVE_COEFFICIENTS,
    check_tyre as check_tyre,
    coefficient_ranges as coefficient_ranges,
    tyre_checked as _tyre_checked,
)
from ._curves import (
    PureSlipCurves as PureSlipCurves,
    combined_slip_curves as combined_slip_curves,
    default_loads as default_loads,
    peak_table as peak_table,
    pure_slip_curves as pure_slip_curves,
)
from ._fit import (
    DEFAULT_STAGES as DEFAULT_STAGES,
    FitReport as FitReport,
    FitStage as FitStage,
    TyreMeasurements as TyreMeasurements,
    fit_tir as fit_tir,
    read_tyre_csv as read_tyre_csv,
    write_tyre_csv as write_tyre_csv,
)
from ._model import (
    ASYMMETRIC_COEFFICIENTS as ASYMMETRIC_COEFFICIENTS,
    SUPPORTED_FITTYP as SUPPORTED_FITTYP,
    MagicFormulaTyre as MagicFormulaTyre,
    coefficient_names as coefficient_names,
    mirror_symmetric as mirror_symmetric,
    stack_tyres as stack_tyres,
)
from ._plot import PANEL_FILES as PANEL_FILES, fig_b1_figures as fig_b1_figures, plot_fig_b1 as plot_fig_b1
from ._tir import (
    TirError as TirError,
    format_tir as format_tir,
    fsae_tir_path as fsae_tir_path,
    load_fsae_tyre as load_fsae_tyre,
    parse_tir as parse_tir,
    read_tir as read_tir,
    write_tir as write_tir,
)
from ._transient import low_speed_denominator as low_speed_denominator

tyre_forces = _tyre_checked(_magic_formula.tyre_forces)
relaxation_lengths = _tyre_checked(_transient.relaxation_lengths)
steady_slips = _tyre_checked(_transient.steady_slips)
transient_slip_rhs = _tyre_checked(_transient.transient_slip_rhs)
transient_slips = _tyre_checked(_transient.transient_slips)
effective_rolling_radius = _tyre_checked(_vertical.effective_rolling_radius)
loaded_radius = _tyre_checked(_vertical.loaded_radius)
vertical_force = _tyre_checked(_vertical.vertical_force)
