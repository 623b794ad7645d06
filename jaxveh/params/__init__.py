"""Vehicle parameters: Equinox pytrees in SI units, loaded from TOML data files."""

from .._core import as_float as as_float, float_field as float_field
from ._appendix_a import (
    TYRE_RANGES as TYRE_RANGES,
    VEHICLE_RANGES as VEHICLE_RANGES,
    VEHICLE_RELATIONS as VEHICLE_RELATIONS,
    AnalyticVehicle as AnalyticVehicle,
    AxleTyre as AxleTyre,
    analytic_vehicle_from_dict as analytic_vehicle_from_dict,
    check_analytic_vehicle as check_analytic_vehicle,
    check_axle_tyre as check_axle_tyre,
    load_analytic_vehicle as load_analytic_vehicle,
)
from ._appendix_b import (
    CORNERS as CORNERS,
    HARD_POINT_NAMES as HARD_POINT_NAMES,
    SPRUNG_HARD_POINTS as SPRUNG_HARD_POINTS,
    CornerHardPoints as CornerHardPoints,
    RigidBodyData as RigidBodyData,
    TyreData as TyreData,
    UnsprungData as UnsprungData,
    VehicleData as VehicleData,
    hard_points_vehicle_frame as hard_points_vehicle_frame,
    load_vehicle_data as load_vehicle_data,
    vehicle_data_from_dict as vehicle_data_from_dict,
)
from ._car_file import (
    CarFile as CarFile,
    read_car_file as read_car_file,
)
from ._checks import (
    NON_NEGATIVE as NON_NEGATIVE,
    POSITIVE as POSITIVE,
    Range as Range,
    check as check,
    check_int as check_int,
    check_module as check_module,
    check_static as check_static,
    checked_field as checked_field,
    require as require,
)
from ._paths import get_at as get_at, parse_path as parse_path, set_all as set_all, set_at as set_at
from ._schema import (
    UNIT_TO_SI as UNIT_TO_SI,
    ParameterError as ParameterError,
    Quantity as Quantity,
    read_section as read_section,
    read_toml as read_toml,
)
