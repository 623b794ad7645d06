"""Fig. 7.8: frequency response to steering at 50 km/h of the linearised car, rigid vs
6-mode flexible chassis: yaw rate and lateral acceleration per degree of steering-wheel
angle, magnitude and phase, 0.1-20 Hz (exact transfer functions of the linearisation about
straight running; tests/test_manoeuvre_frequency.py checks them against the swept-sine time
run)."""

import numpy as np
from _util import output_dir, write_json

from jaxveh.analysis import linear_frequency_response, linearise
from jaxveh.plots import plot_frequency_response, save
from jaxveh.vehicle import load_car

SPEED = 50.0 / 3.6
FREQUENCIES = np.logspace(-1.0, np.log10(20.0), 300)


def main():
    out = output_dir("fig_7_8", __doc__)
    responses = {label: linear_frequency_response(linearise(load_car(modes=modes), SPEED), FREQUENCIES)
                 for label, modes in (("rigid", 0), ("flexible, 6 modes", 6))}
    save(plot_frequency_response(responses, title="frequency response to steering at 50 km/h (Fig. 7.8)"),
         out / "fig_7_8.png")
    write_json(responses, out / "fig_7_8.json")
    for label, r in responses.items():
        f = np.asarray(r["frequency_hz"])
        for name in ("yaw_rate", "ay"):
            gain = np.asarray(r[f"{name}_gain"])
            at2 = np.interp(2.0, f, gain) / gain[0]
            at10 = np.interp(10.0, f, gain) / gain[0]
            print(f"{label:>18} {name:>8}: gain at 2 Hz {at2:.3f}, at 10 Hz {at10:.4f} of the 0.1 Hz gain; phase at "
                  f"2 Hz {np.interp(2.0, f, r[f'{name}_phase_deg']):.1f} deg")


if __name__ == "__main__":
    main()
