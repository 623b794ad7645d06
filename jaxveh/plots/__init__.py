"""Matplotlib figures in the style of the thesis (Agg backend, PNG output)."""

from ._chapter3 import (
    figure as figure,
    plot_bode as plot_bode,
    plot_design_curves as plot_design_curves,
    plot_map as plot_map,
    plot_preview as plot_preview,
    plot_root_locus as plot_root_locus,
    plot_skidpad as plot_skidpad,
    plot_step_steer as plot_step_steer,
    save as save,
)
from ._kinematics import (
    plot_car_preview as plot_car_preview,
    plot_kinematic_gradients as plot_kinematic_gradients,
    plot_modal_coordinates as plot_modal_coordinates,
    plot_projection_matrices as plot_projection_matrices,
    plot_simplifications as plot_simplifications,
)
from ._manoeuvres import (
    BRAKE_IN_TURN_PANELS as BRAKE_IN_TURN_PANELS,
    STRAIGHT_LINE_PANELS as STRAIGHT_LINE_PANELS,
    plot_four_post as plot_four_post,
    plot_frequency_response as plot_frequency_response,
    plot_manoeuvre as plot_manoeuvre,
    plot_skid_pad as plot_skid_pad,
)
from ._rigs import (
    plot_bump as plot_bump,
    plot_roll as plot_roll,
    plot_steer as plot_steer,
)
