"""Manoeuvres on the chapter-6 car: open-loop steering laws with a held speed
(:mod:`._driver`), the four-post rig's road input (:mod:`._road`), the closed-loop
pure-pursuit driver on reference paths (:mod:`._pursuit`, :mod:`._paths`: skid-pad circle,
ISO 3888-1 lane change), integration from straight running
in the fast or the library form with named channels (:mod:`._simulate`, :mod:`._channels`);
steady states (straight running, steady cornering, the skid-pad curve) of the fast car by
root finding (:mod:`._steady`)."""

from ._channels import PATH_CHANNELS as PATH_CHANNELS, UNITS as UNITS, car_channels as car_channels
from ._driver import (
    AbstractSteeringLaw as AbstractSteeringLaw,
    Manoeuvre as Manoeuvre,
    RampSteer as RampSteer,
    StepSteer as StepSteer,
    Straight as Straight,
    SweptSine as SweptSine,
    accelerate as accelerate,
    brake as brake,
    brake_in_turn as brake_in_turn,
    kink_times as kink_times,
    step_steer as step_steer,
)
from ._export import run_dataset as run_dataset, write_netcdf as write_netcdf
from ._metrics import (
    BRAKE_IN_TURN_AFTER as BRAKE_IN_TURN_AFTER,
    brake_in_turn_metrics as brake_in_turn_metrics,
    constant_radius_metrics as constant_radius_metrics,
    four_post_metrics as four_post_metrics,
    frequency_response as frequency_response,
    lane_change_metrics as lane_change_metrics,
    ramp_steer_metrics as ramp_steer_metrics,
    step_steer_metrics as step_steer_metrics,
    straight_line_hold as straight_line_hold,
    straight_line_means as straight_line_means,
    straight_line_metrics as straight_line_metrics,
)
from ._paths import (
    ISO_3888_1_SECTIONS as ISO_3888_1_SECTIONS,
    AbstractPath as AbstractPath,
    Circle as Circle,
    DoubleLaneChange as DoubleLaneChange,
)
from ._pursuit import (
    PurePursuit as PurePursuit,
    car_width as car_width,
    constant_radius as constant_radius,
    lane_change as lane_change,
    pure_pursuit as pure_pursuit,
    steering_ratio as steering_ratio,
)
from ._reports import skid_pad_grid as skid_pad_grid, skid_pad_report as skid_pad_report
from ._road import (
    POST_PATTERNS as POST_PATTERNS,
    PostSweep as PostSweep,
    four_post as four_post,
)
from ._simulate import (
    AUTO_IMEX_RTOL as AUTO_IMEX_RTOL,
    EVENTS as EVENTS,
    IMEX_SOLVERS as IMEX_SOLVERS,
    SOLVERS as SOLVERS,
    CarRun as CarRun,
    manoeuvre_channels as manoeuvre_channels,
    pick_solver as pick_solver,
    save_times as save_times,
    simulate as simulate,
    start_trim as start_trim,
    straight_trim as straight_trim,
)
from ._steady import (
    CONDITIONS as CONDITIONS,
    SkidPad as SkidPad,
    SteadyCornering as SteadyCornering,
    StraightTrim as StraightTrim,
    circle_steer as circle_steer,
    circle_steer_core as circle_steer_core,
    skid_pad as skid_pad,
    skid_pad_core as skid_pad_core,
    steady_state as steady_state,
)
