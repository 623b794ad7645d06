"""Chapter-7 analyses of the chapter-6 car: lateral load transfer and its distribution χ
(section 7.1.2, Fig. 7.2) against ay, the roll stiffness distribution λ, the number of
chassis modes and each mode's stiffness, beside the chapter-3 model (eqs. 3.2-3.6) fed
with the car's own parameters; the suspension kinematics under chassis deformation
(projection matrices, Table 7.1's kinematic gradients, modal coordinates on the skid-pad);
exact linearisation, eigenvalue derivatives and root loci. See docs/analysis.md."""

from ._chapter3 import (
    Chapter3Parameters as Chapter3Parameters,
    analytic_vehicle as analytic_vehicle,
    chapter3_chi as chapter3_chi,
    chapter3_load_transfer as chapter3_load_transfer,
    chapter3_parameters as chapter3_parameters,
    frame_torsional_stiffness as frame_torsional_stiffness,
    roll_centre_heights as roll_centre_heights,
    static_sink as static_sink,
    with_lambda as with_lambda,
)
from ._kinematics import (
    THESIS_TABLE_7_1 as THESIS_TABLE_7_1,
    WHEEL_PARAMETERS as WHEEL_PARAMETERS,
    KinematicGradients as KinematicGradients,
    ProjectionMatrices as ProjectionMatrices,
    gradient_table as gradient_table,
    kinematic_gradients as kinematic_gradients,
    kinematic_gradients_report as kinematic_gradients_report,
    modal_ay_dependence as modal_ay_dependence,
    modes_vs_sprung_mass as modes_vs_sprung_mass,
    projection_matrices as projection_matrices,
    wheel_parameters as wheel_parameters,
)
from ._linear import (
    DEFAULT_OUTPUTS as DEFAULT_OUTPUTS,
    FRF_OUTPUTS as FRF_OUTPUTS,
    INPUTS as INPUTS,
    CarLinearisation as CarLinearisation,
    eigenvalue_sensitivities as eigenvalue_sensitivities,
    input_direction as input_direction,
    linear_field as linear_field,
    linear_frequency_response as linear_frequency_response,
    linear_tangent as linear_tangent,
    linearise as linearise,
    linearise_core as linearise_core,
    modes as modes,
    output_index as output_index,
    stiffness_direction as stiffness_direction,
    transfer_function as transfer_function,
)
from ._load_transfer import (
    AY_GRID_G as AY_GRID_G,
    FREEZE as FREEZE,
    LAMBDA_RANGE as LAMBDA_RANGE,
    LOW_AY_G as LOW_AY_G,
    LOW_AY_PAIR_G as LOW_AY_PAIR_G,
    MU_RANGE as MU_RANGE,
    SKID_PAD_RADIUS as SKID_PAD_RADIUS,
    LoadTransfer as LoadTransfer,
    arb_rates_for_distribution as arb_rates_for_distribution,
    chi_by_modes as chi_by_modes,
    chi_mode_stiffness_gradient as chi_mode_stiffness_gradient,
    chi_vs_lambda as chi_vs_lambda,
    chi_vs_mode_stiffness as chi_vs_mode_stiffness,
    chi_vs_modes as chi_vs_modes,
    lambda_designs as lambda_designs,
    load_transfer as load_transfer,
    load_transfer_batch as load_transfer_batch,
    load_transfer_core as load_transfer_core,
    mode_stiffness_designs as mode_stiffness_designs,
    truncation_designs as truncation_designs,
)
from ._preview import (
    PreviewResult as PreviewResult,
    car_preview as car_preview,
    preview_by_modes as preview_by_modes,
    preview_core as preview_core,
    preview_distance_sensitivity as preview_distance_sensitivity,
    preview_report as preview_report,
    preview_vs_mode_stiffness as preview_vs_mode_stiffness,
)
from ._reports import lltd_report as lltd_report
from ._root_locus import (
    SWEEPS as SWEEPS,
    RootLocus as RootLocus,
    first_chassis_mode as first_chassis_mode,
    kinetic_energy_shares as kinetic_energy_shares,
    mode_label as mode_label,
    root_locus as root_locus,
    root_locus_report as root_locus_report,
)
from ._simplifications import (
    FREEZE_STEPS as FREEZE_STEPS,
    SIMPLIFICATIONS as SIMPLIFICATIONS,
    simplification_study as simplification_study,
    table_7_2_step_steer as table_7_2_step_steer,
    variant_car as variant_car,
)
