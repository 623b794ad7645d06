"""The chapter-6 vehicle, built with :mod:`jaxveh.multibody` (today: one corner).

``quarter_car`` builds the front-left (or rear-left) double-wishbone corner from the
Appendix B hard points on a fixed chassis; ``quarter_car_kinematics`` sweeps it (camber,
toe, track, wheel centre) and raises :class:`jaxveh.multibody.AssemblyError` for a travel
that cannot be reached (or flags it in jitted sweeps).
"""

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
