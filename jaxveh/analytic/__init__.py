"""Chapter-3 analytic models: load transfer, roll steer, the non-linear 4-DOF vehicle,
its linearisation, root locus, frequency response and steady-state / transient analyses.

Every function here that takes an :class:`~jaxveh.params.AnalyticVehicle` checks it first
(field ranges and relations, ``ParameterError`` for concrete values, ``eqx.error_if`` for
traced ones), and a ``speed`` argument > 0; see "Input validation" in ``docs/analytic.md``.
"""

from . import _linear, _load_transfer, _model, _modes, _quantities, _roll_steer, _steady, _transient, _tyre
from ._checks import tyre_checked as _tyre_checked, vehicle_checked as _vehicle_checked
from ._inputs import AbstractSteer as AbstractSteer, ConstantSteer as ConstantSteer, SmoothStep as SmoothStep
from ._linear import (
    LINEAR_STATE_NAMES as LINEAR_STATE_NAMES,
    RIGID_STATE_NAMES as RIGID_STATE_NAMES,
    dynamic_subsystem as dynamic_subsystem,
)
from ._model import (
    FLEXIBLE as FLEXIBLE,
    RIGID as RIGID,
    STATE_NAMES as STATE_NAMES,
    VARIANTS as VARIANTS,
    Variant as Variant,
    get_variant as get_variant,
)
from ._quantities import GRAVITY as GRAVITY
from ._roll_steer import RAD_PER_MS2_TO_DEG_PER_G as RAD_PER_MS2_TO_DEG_PER_G
from ._steady import SteadyState as SteadyState
from ._transient import Trajectory as Trajectory, step_steer_metrics as step_steer_metrics

# Linear model (3.29)-(3.37)
linearise = _vehicle_checked(_linear.linearise)
second_order_matrices = _vehicle_checked(_linear.second_order_matrices)
state_space = _vehicle_checked(_linear.state_space)
# Load transfer (3.2)-(3.7)
chi = _vehicle_checked(_load_transfer.chi)
chi_from_transfer = _vehicle_checked(_load_transfer.chi_from_transfer)
chi_rigid = _vehicle_checked(_load_transfer.chi_rigid)
chi_sensitivity = _vehicle_checked(_load_transfer.chi_sensitivity)
load_transfer_flexible = _vehicle_checked(_load_transfer.load_transfer_flexible)
load_transfer_rigid = _vehicle_checked(_load_transfer.load_transfer_rigid)
load_transfer_summary = _vehicle_checked(_load_transfer.load_transfer_summary)
zeta = _vehicle_checked(_load_transfer.zeta)
# Non-linear 4-DOF model (3.17)-(3.28)
axle_forces = _vehicle_checked(_model.axle_forces)
lateral_acceleration = _vehicle_checked(_model.lateral_acceleration)
mass_matrix = _vehicle_checked(_model.mass_matrix)
vector_field = _vehicle_checked(_model.vector_field)
# Modes and frequency response
eigenvalues = _vehicle_checked(_modes.eigenvalues)
frequency_response = _vehicle_checked(_modes.frequency_response)
vehicle_modes = _vehicle_checked(_modes.vehicle_modes)
# Derived quantities and the (λ, µ) parametrisation
normalised_torsional_stiffness = _vehicle_checked(_quantities.normalised_torsional_stiffness)
roll_gradient = _vehicle_checked(_quantities.roll_gradient)
roll_moment_proportion = _vehicle_checked(_quantities.roll_moment_proportion)
roll_stiffness_proportion = _vehicle_checked(_quantities.roll_stiffness_proportion)
static_tyre_loads = _vehicle_checked(_quantities.static_tyre_loads)
with_distribution = _vehicle_checked(_quantities.with_distribution)
# Roll steer and understeer (3.8)-(3.16)
axle_cornering_stiffness = _vehicle_checked(_roll_steer.axle_cornering_stiffness)
chassis_twist = _vehicle_checked(_roll_steer.chassis_twist)
roll_angles_flexible = _vehicle_checked(_roll_steer.roll_angles_flexible)
roll_angles_normalised = _vehicle_checked(_roll_steer.roll_angles_normalised)
understeer_gradient = _vehicle_checked(_roll_steer.understeer_gradient)
understeer_gradient_rigid = _vehicle_checked(_roll_steer.understeer_gradient_rigid)
understeer_summary = _vehicle_checked(_roll_steer.understeer_summary)
# Skid-pad and step steer
skidpad_steady_state = _vehicle_checked(_steady.skidpad_steady_state)
skidpad_sweep = _vehicle_checked(_steady.skidpad_sweep)
steering_sensitivity = _vehicle_checked(_steady.steering_sensitivity)
simulate = _vehicle_checked(_transient.simulate)
# Tyre of (3.27)
axle_force = _tyre_checked(_tyre.axle_force)
cornering_stiffness = _tyre_checked(_tyre.cornering_stiffness)
lateral_force = _tyre_checked(_tyre.lateral_force)
