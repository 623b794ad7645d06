"""Flexible multibody library (thesis chapter 5) as pure JAX.

Rigid and modal-flexible bodies in reference-point coordinates, link / spherical / revolute
joints, tree revolute joints, rheonomic inputs, a semi-recursive velocity transformation
``v = T y`` and the velocity projection ``y = R z + S b`` that turns the constrained DAE
into an ODE in independent velocities (eq. 5.61). Nothing here knows about vehicles.
"""

from ._bodies import (
    AbstractBody as AbstractBody,
    FlexibleBody as FlexibleBody,
    FlexOptions as FlexOptions,
    RigidBody as RigidBody,
)
from ._dynamics import (
    body_forces as body_forces,
    body_quadratic_forces as body_quadratic_forces,
    body_torque as body_torque,
    energy as energy,
    internal_forces as internal_forces,
    mass_matrix as mass_matrix,
    point_force as point_force,
)
from ._errors import (
    AssemblyError as AssemblyError,
    MultibodyError as MultibodyError,
    RedundantConstraintError as RedundantConstraintError,
    SingularMassMatrixError as SingularMassMatrixError,
)
from ._forces import (
    AbstractForceElement as AbstractForceElement,
    Bushing as Bushing,
    ElementForces as ElementForces,
    FirstOrderLag as FirstOrderLag,
    Kinematics as Kinematics,
    SpringDamper as SpringDamper,
    TorsionSpring as TorsionSpring,
    aux_names as aux_names,
    element_forces as element_forces,
    generalised_forces as generalised_forces,
    kinematics as kinematics,
    zero_forces as zero_forces,
)
from ._imex import (
    ModalImplicitPart as ModalImplicitPart,
    modal_implicit_part as modal_implicit_part,
)
from ._inputs import (
    AbstractInputs as AbstractInputs,
    StateInputs as StateInputs,
    TimeInputs as TimeInputs,
)
from ._kinematics import (
    body_poses as body_poses,
    body_rotation as body_rotation,
    body_velocities as body_velocities,
    constraint_jacobian as constraint_jacobian,
    constraints as constraints,
    marker_input_jacobian as marker_input_jacobian,
    marker_jacobian as marker_jacobian,
    marker_positions as marker_positions,
    point_velocity as point_velocity,
    recursion_matrix as recursion_matrix,
    recursion_matrix_dot as recursion_matrix_dot,
    velocity_maps as velocity_maps,
    velocity_matrix as velocity_matrix,
    velocity_matrix_b as velocity_matrix_b,
    velocity_matrix_dot as velocity_matrix_dot,
)
from ._linear import (
    Linearisation as Linearisation,
    chart as chart,
    linearise as linearise,
    minimal_rates as minimal_rates,
)
from ._projection import (
    Dynamics as Dynamics,
    Projection as Projection,
    check_mass_matrix as check_mass_matrix,
    check_rank as check_rank,
    dynamics as dynamics,
    input_state as input_state,
    input_values as input_values,
    multipliers as multipliers,
    projection as projection,
)
from ._rotations import (
    angular_velocity_matrix as angular_velocity_matrix,
    axis_angle as axis_angle,
    rotation_matrix as rotation_matrix,
    skew as skew,
)
from ._simulate import (
    ASSEMBLY_TOL as ASSEMBLY_TOL,
    DEFAULT_KAPPA as DEFAULT_KAPPA,
    MAX_BRANCH_ROTATION as MAX_BRANCH_ROTATION,
    AssemblyResult as AssemblyResult,
    ProjectedSolver as ProjectedSolver,
    Simulation as Simulation,
    State as State,
    assemble as assemble,
    assembly_message as assembly_message,
    default_imex_solver as default_imex_solver,
    independent_velocities as independent_velocities,
    joint_velocities as joint_velocities,
    project_coordinates as project_coordinates,
    simulate as simulate,
    solve_assembly as solve_assembly,
    vector_field as vector_field,
)
from ._system import (
    GROUND as GROUND,
    System as System,
    SystemBuilder as SystemBuilder,
    SystemParams as SystemParams,
    checked_params as checked_params,
)
from ._trim import (
    TRIM_ATOL as TRIM_ATOL,
    Trim as Trim,
    TrimError as TrimError,
    trim as trim,
)
