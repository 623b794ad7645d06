"""The chapter-6 vehicle, built with :mod:`jaxveh.multibody`: the assembled 14-DOF car with
its flexible chassis (``load_car``), its static set-up, kinematic rigs and rates, and its
parts; and the same car's equations in minimal coordinates (``fast_model``,
``fast_dynamics``: corner kinematics solved exactly, four corners vectorised).

``quarter_car`` builds the front-left (or rear-left) double-wishbone corner from the
Appendix B hard points on a fixed chassis; ``quarter_car_kinematics`` sweeps it (camber,
toe, track, wheel centre) and raises :class:`jaxveh.multibody.AssemblyError` for a travel
that cannot be reached (or flags it in jitted sweeps). The push-rod path (section 6.1.5,
eqs. 6.4-6.12): wishbone frame and point D, the closed-form rocker angle, spring length,
the rocker's moment balance and the wishbone's load distribution; and the suspension rates
they imply (installation ratios, wheel and ride rates, roll stiffness, λ; docs/vehicle.md).
"""

from ._aero import (
    AeroLoads as AeroLoads,
    AeroMap as AeroMap,
    aero_map_from_coefficients as aero_map_from_coefficients,
)
from ._car import (
    CORNER_KEYS as CORNER_KEYS,
    CORNERS as CORNERS,
    FORMS as FORMS,
    MAX_MODES as MAX_MODES,
    Car as Car,
    CarParams as CarParams,
    car_elements as car_elements,
    check_car as check_car,
    check_form as check_form,
    design_coordinates as design_coordinates,
    design_spring_lengths as design_spring_lengths,
    load_car as load_car,
    rest_spring_preloads as rest_spring_preloads,
    set_car_params as set_car_params,
    speed_feedforward as speed_feedforward,
    sprung_cg as sprung_cg,
    static_corner_loads as static_corner_loads,
    steering as steering,
    steering_rack as steering_rack,
    system_params as system_params,
    total_mass as total_mass,
    wheel_centres as wheel_centres,
    with_params as with_params,
    with_rest_preloads as with_rest_preloads,
)
from ._contact import (
    WHEEL_STATES as WHEEL_STATES,
    AbstractRoad as AbstractRoad,
    FlatRoad as FlatRoad,
    PostRoad as PostRoad,
    TyreContact as TyreContact,
    contact_geometry as contact_geometry,
    wheel_contact as wheel_contact,
)
from ._corner import (
    QUARTER_CAR_LINKS as QUARTER_CAR_LINKS,
    WHEEL_CENTRE_HEIGHT as WHEEL_CENTRE_HEIGHT,
    WheelRate as WheelRate,
    quarter_car as quarter_car,
    quarter_car_design_q as quarter_car_design_q,
    quarter_car_kinematics as quarter_car_kinematics,
    quarter_car_wheel_centre as quarter_car_wheel_centre,
    quarter_car_with_hard_points as quarter_car_with_hard_points,
    wheel_angles as wheel_angles,
)
from ._corner_kinematics import (
    CornerGeometry as CornerGeometry,
    CornerMotion as CornerMotion,
    KinematicMap as KinematicMap,
    build_map as build_map,
    corner_geometry as corner_geometry,
    corner_motion as corner_motion,
    corner_poses as corner_poses,
    map_guess as map_guess,
    pose_residual as pose_residual,
)
from ._fast import (
    FastDynamics as FastDynamics,
    FastModel as FastModel,
    FastState as FastState,
    fast_dynamics as fast_dynamics,
    fast_model as fast_model,
    fast_state_from_library as fast_state_from_library,
    travel_from_library as travel_from_library,
)
from ._powertrain import (
    POWERTRAIN_STATES as POWERTRAIN_STATES,
    AbstractSpeedTarget as AbstractSpeedTarget,
    ConstantSpeed as ConstantSpeed,
    Powertrain as Powertrain,
    SpeedChange as SpeedChange,
    SpeedPID as SpeedPID,
)
from ._pushrod import (
    RockerGeometry as RockerGeometry,
    RockerLoads as RockerLoads,
    RockerMount as RockerMount,
    WishboneGeometry as WishboneGeometry,
    WishboneLoads as WishboneLoads,
    beam_loads as beam_loads,
    point_d as point_d,
    rocker_angle as rocker_angle,
    rocker_geometry as rocker_geometry,
    rocker_loads as rocker_loads,
    rocker_mount as rocker_mount,
    rocker_on_chassis as rocker_on_chassis,
    rocker_reach as rocker_reach,
    rotate_about_axis as rotate_about_axis,
    spring_length as spring_length,
    wishbone_frame as wishbone_frame,
    wishbone_geometry as wishbone_geometry,
    wishbone_loads as wishbone_loads,
)
from ._rates import (
    AxleRates as AxleRates,
    InstallationRatios as InstallationRatios,
    axle_rates as axle_rates,
    corner_sprung_masses as corner_sprung_masses,
    design_rates as design_rates,
    installation_ratios as installation_ratios,
    roll_stiffness_distribution as roll_stiffness_distribution,
)
from ._report import (
    bump_report as bump_report,
    car_rates as car_rates,
    roll_report as roll_report,
    spring_at_design as spring_at_design,
    steer_report as steer_report,
    vehicle_info as vehicle_info,
)
from ._rigs import (
    bump_rig as bump_rig,
    check_rig as check_rig,
    roll_rig as roll_rig,
    steer_rig as steer_rig,
)
from ._setup import (
    SetupError as SetupError,
    StaticState as StaticState,
    SteadyState as SteadyState,
    chassis_twist as chassis_twist,
    static_equilibrium as static_equilibrium,
    straight_running as straight_running,
)
from ._springs import (
    BUMP_STOP_ROUNDING as BUMP_STOP_ROUNDING,
    SpringDamperLaw as SpringDamperLaw,
    interpolate as interpolate,
    linear_spring_damper as linear_spring_damper,
)
from ._suspension import (
    CORNER_POINTS as CORNER_POINTS,
    PushrodSuspension as PushrodSuspension,
    corner_forces as corner_forces,
    corner_state as corner_state,
    pushrod_suspension as pushrod_suspension,
)
