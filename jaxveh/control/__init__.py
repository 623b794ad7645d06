"""Linear-quadratic control: ZOH discretisation, Butterworth filters, discrete Riccati
solver and the time-invariant optimal preview controller of thesis section 3.3.6.

Generic: nothing here knows about vehicles. A vehicle model supplies continuous-time
``(a_c, b_c)`` and the output row selecting the lateral position.
"""

from ._butterworth import (
    DiscreteStateSpace as DiscreteStateSpace,
    butterworth_lowpass as butterworth_lowpass,
)
from ._discretise import zoh as zoh
from ._preview import (
    PreviewGains as PreviewGains,
    PreviewPlant as PreviewPlant,
    preview_controller as preview_controller,
    preview_distance as preview_distance,
    preview_plant as preview_plant,
)
from ._riccati import (
    RESULTS as RESULTS,
    DareSolution as DareSolution,
    riccati_gain as riccati_gain,
    riccati_residual as riccati_residual,
    solve_dare as solve_dare,
)
