"""Figs 7.1, 7.3, 7.4 and Table 7.1: the chassis's effect on the suspension kinematics of the
6-mode car on the 50 m skid-pad (steady states by root finding, turning left). Fig. 7.1:
the modal coordinates against ay and against the sprung mass at 0.3 g, with each mode's ay
dependence classified; Fig. 7.3: the projection matrices TR and R at straight running
(50 km/h), R's wheel-parameter signs as triangles; Fig. 7.4 and Table 7.1: camber
(inclination) and toe-in change per g due to the chassis, left wheels, full model against
the linear approximation, beside the thesis's values."""

import numpy as np
from _util import output_dir, write_json

from jaxveh.analysis import kinematic_gradients_report, modes_vs_sprung_mass, projection_matrices
from jaxveh.plots import plot_kinematic_gradients, plot_modal_coordinates, plot_projection_matrices, save
from jaxveh.vehicle import load_car

RADIUS, AY_REF_G = 50.0, 0.3
MASSES = np.linspace(150.0, 350.0, 5)  # kg, Fig. 7.1b's range


def main():
    out = output_dir("fig_7_1_7_4", __doc__)
    car = load_car(modes=6)
    report = kinematic_gradients_report(car, RADIUS, AY_REF_G)
    by_mass = np.asarray(modes_vs_sprung_mass(car, MASSES, ay_g=AY_REF_G, radius=RADIUS))
    report["modes_vs_sprung_mass"] = {"sprung_mass_kg": MASSES.tolist(), "ay_g": AY_REF_G, "modes": by_mass.tolist()}
    mc = report["modal_coordinates"]
    save(plot_modal_coordinates(mc["ay_g"], mc["modes"], MASSES, by_mass,
                                title=f"modal coordinates on the {RADIUS:g} m skid-pad (Fig. 7.1; right: at "
                                f"{AY_REF_G} g)"), out / "fig_7_1.png")
    pm = projection_matrices(car)
    save(plot_projection_matrices(pm, title="projection matrices at 50 km/h straight running (Fig. 7.3)"),
         out / "fig_7_3.png")
    report["projection_matrices"] = {"rows": list(pm.rows), "columns": list(pm.columns),
                                     "r": np.asarray(pm.r).tolist(), "tr": np.asarray(pm.tr).tolist()}
    save(plot_kinematic_gradients(report, title=f"effect of the chassis on the kinematics, R = {RADIUS:g} m "
                                  "(Fig. 7.4)"), out / "fig_7_4.png")
    write_json(report, out / "fig_7_1_7_4.json")
    print(f"Table 7.1 at {report['reference_ay_g']:.2f} g (left wheels; thesis in brackets):")
    for axle in ("front", "rear"):
        r, t = report[axle], report["thesis_table_7_1"][axle]
        print(f"  {axle:>5}: camber {r['camber_deg_per_g']:+.4f} ({t['camber_deg_per_g']:+.3f}) deg/g, "
              f"toe-in {r['toe_deg_per_g']:+.4f} ({t['toe_deg_per_g']:+.3f}) deg/g")
    for d in report["modal_ay_dependence"]:
        print(f"  mode {d['mode']}: change over 0-1.2 g {100 * d['relative_change']:5.1f} %, R^2 "
              f"{d['r_squared']:.3f} -> {'depends on ay' if d['depends_on_ay'] else 'does not depend on ay'}")


if __name__ == "__main__":
    main()
