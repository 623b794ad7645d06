"""Chapter-3 analytic models: load transfer, roll steer, the non-linear 4-DOF vehicle,
its linearisation, root locus, frequency response and steady-state / transient analyses."""

from ._inputs import AbstractSteer as AbstractSteer, ConstantSteer as ConstantSteer, SmoothStep as SmoothStep
from ._linear import (
    LINEAR_STATE_NAMES as LINEAR_STATE_NAMES,
    RIGID_STATE_NAMES as RIGID_STATE_NAMES,
    dynamic_subsystem as dynamic_subsystem,
    linearise as linearise,
    second_order_matrices as second_order_matrices,
    state_space as state_space,
)
from ._load_transfer import (
    chi as chi,
    chi_from_transfer as chi_from_transfer,
    chi_rigid as chi_rigid,
    chi_sensitivity as chi_sensitivity,
    load_transfer_flexible as load_transfer_flexible,
    load_transfer_rigid as load_transfer_rigid,
    load_transfer_summary as load_transfer_summary,
    zeta as zeta,
)
from ._model import (
    FLEXIBLE as FLEXIBLE,
    RIGID as RIGID,
    STATE_NAMES as STATE_NAMES,
    VARIANTS as VARIANTS,
    Variant as Variant,
    axle_forces as axle_forces,
    get_variant as get_variant,
    lateral_acceleration as lateral_acceleration,
    mass_matrix as mass_matrix,
    vector_field as vector_field,
)
from ._modes import eigenvalues as eigenvalues, frequency_response as frequency_response, vehicle_modes as vehicle_modes
from ._quantities import (
    GRAVITY as GRAVITY,
    normalised_torsional_stiffness as normalised_torsional_stiffness,
    roll_gradient as roll_gradient,
    roll_moment_proportion as roll_moment_proportion,
    roll_stiffness_proportion as roll_stiffness_proportion,
    static_tyre_loads as static_tyre_loads,
    with_distribution as with_distribution,
)
from ._roll_steer import (
    RAD_PER_MS2_TO_DEG_PER_G as RAD_PER_MS2_TO_DEG_PER_G,
    axle_cornering_stiffness as axle_cornering_stiffness,
    chassis_twist as chassis_twist,
    roll_angles_flexible as roll_angles_flexible,
    roll_angles_normalised as roll_angles_normalised,
    understeer_gradient as understeer_gradient,
    understeer_gradient_rigid as understeer_gradient_rigid,
    understeer_summary as understeer_summary,
)
from ._steady import (
    SteadyState as SteadyState,
    skidpad_steady_state as skidpad_steady_state,
    skidpad_sweep as skidpad_sweep,
    steering_sensitivity as steering_sensitivity,
)
from ._transient import Trajectory as Trajectory, simulate as simulate, step_steer_metrics as step_steer_metrics
from ._tyre import axle_force as axle_force, cornering_stiffness as cornering_stiffness, lateral_force as lateral_force
