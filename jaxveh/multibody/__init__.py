"""Flexible multibody library (thesis chapter 5) as pure JAX.

Rigid and modal-flexible bodies in reference-point coordinates, link / spherical / revolute
joints, tree revolute joints, rheonomic inputs, a semi-recursive velocity transformation
``v = T y`` and the velocity projection ``y = R z + S b`` that turns the constrained DAE
into an ODE in independent velocities (eq. 5.61). Nothing here knows about vehicles.
"""

from ._bodies import (
    FlexibleBody as FlexibleBody,
)
from ._bodies import (
    FlexOptions as FlexOptions,
)
from ._bodies import (
    RigidBody as RigidBody,
)
from ._dynamics import (
    body_quadratic_forces as body_quadratic_forces,
)
from ._dynamics import (
    body_torque as body_torque,
)
from ._dynamics import (
    energy as energy,
)
from ._dynamics import (
    internal_forces as internal_forces,
)
from ._dynamics import (
    mass_matrix as mass_matrix,
)
from ._dynamics import (
    point_force as point_force,
)
from ._errors import (
    AssemblyError as AssemblyError,
)
from ._errors import (
    MultibodyError as MultibodyError,
)
from ._errors import (
    RedundantConstraintError as RedundantConstraintError,
)
from ._errors import (
    SingularMassMatrixError as SingularMassMatrixError,
)
from ._forces import (
    AbstractForceElement as AbstractForceElement,
)
from ._forces import (
    Bushing as Bushing,
)
from ._forces import (
    ElementForces as ElementForces,
)
from ._forces import (
    FirstOrderLag as FirstOrderLag,
)
from ._forces import (
    Kinematics as Kinematics,
)
from ._forces import (
    SpringDamper as SpringDamper,
)
from ._forces import (
    TorsionSpring as TorsionSpring,
)
from ._forces import (
    aux_names as aux_names,
)
from ._forces import (
    generalised_forces as generalised_forces,
)
from ._forces import (
    kinematics as kinematics,
)
from ._forces import (
    zero_forces as zero_forces,
)
from ._inputs import (
    AbstractInputs as AbstractInputs,
)
from ._inputs import (
    StateInputs as StateInputs,
)
from ._inputs import (
    TimeInputs as TimeInputs,
)
from ._kinematics import (
    body_poses as body_poses,
)
from ._kinematics import (
    body_rotation as body_rotation,
)
from ._kinematics import (
    body_velocities as body_velocities,
)
from ._kinematics import (
    constraint_jacobian as constraint_jacobian,
)
from ._kinematics import (
    constraints as constraints,
)
from ._kinematics import (
    marker_input_jacobian as marker_input_jacobian,
)
from ._kinematics import (
    marker_jacobian as marker_jacobian,
)
from ._kinematics import (
    marker_positions as marker_positions,
)
from ._kinematics import (
    point_velocity as point_velocity,
)
from ._kinematics import (
    recursion_matrix as recursion_matrix,
)
from ._kinematics import (
    recursion_matrix_dot as recursion_matrix_dot,
)
from ._kinematics import (
    velocity_maps as velocity_maps,
)
from ._kinematics import (
    velocity_matrix as velocity_matrix,
)
from ._kinematics import (
    velocity_matrix_b as velocity_matrix_b,
)
from ._kinematics import (
    velocity_matrix_dot as velocity_matrix_dot,
)
from ._linear import (
    Linearisation as Linearisation,
)
from ._linear import (
    chart as chart,
)
from ._linear import (
    linearise as linearise,
)
from ._linear import (
    minimal_rates as minimal_rates,
)
from ._projection import (
    Dynamics as Dynamics,
)
from ._projection import (
    Projection as Projection,
)
from ._projection import (
    check_mass_matrix as check_mass_matrix,
)
from ._projection import (
    check_rank as check_rank,
)
from ._projection import (
    dynamics as dynamics,
)
from ._projection import (
    input_state as input_state,
)
from ._projection import (
    input_values as input_values,
)
from ._projection import (
    multipliers as multipliers,
)
from ._projection import (
    projection as projection,
)
from ._rotations import (
    angular_velocity_matrix as angular_velocity_matrix,
)
from ._rotations import (
    axis_angle as axis_angle,
)
from ._rotations import (
    rotation_matrix as rotation_matrix,
)
from ._rotations import (
    skew as skew,
)
from ._simulate import (
    ASSEMBLY_TOL as ASSEMBLY_TOL,
)
from ._simulate import (
    DEFAULT_KAPPA as DEFAULT_KAPPA,
)
from ._simulate import (
    MAX_BRANCH_ROTATION as MAX_BRANCH_ROTATION,
)
from ._simulate import (
    AssemblyResult as AssemblyResult,
)
from ._simulate import (
    ProjectedSolver as ProjectedSolver,
)
from ._simulate import (
    Simulation as Simulation,
)
from ._simulate import (
    State as State,
)
from ._simulate import (
    assemble as assemble,
)
from ._simulate import (
    assembly_message as assembly_message,
)
from ._simulate import (
    independent_velocities as independent_velocities,
)
from ._simulate import (
    joint_velocities as joint_velocities,
)
from ._simulate import (
    project_coordinates as project_coordinates,
)
from ._simulate import (
    simulate as simulate,
)
from ._simulate import (
    solve_assembly as solve_assembly,
)
from ._simulate import (
    vector_field as vector_field,
)
from ._system import (
    GROUND as GROUND,
)
from ._system import (
    System as System,
)
from ._system import (
    SystemBuilder as SystemBuilder,
)
from ._system import (
    SystemParams as SystemParams,
)
from ._system import (
    checked_params as checked_params,
)
from ._trim import (
    TRIM_ATOL as TRIM_ATOL,
)
from ._trim import (
    Trim as Trim,
)
from ._trim import (
    TrimError as TrimError,
)
from ._trim import (
    trim as trim,
)
