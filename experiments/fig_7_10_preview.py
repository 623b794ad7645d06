"""Fig. 7.10: time-invariant optimal preview control of the linearised 6-mode car at 100
km/h (section 7.5: 250 preview points, dt 0.01 s, tracking weight 1000): (a) the preview
gains, flexible vs rigid; (b) against the chapter-3 model's; (c) the preview distance
against the number of modes; (d) against each mode's stiffness multiplier µ (0.1-10); and
d Lp / d µ_1 by forward mode beside central differences."""

import equinox as eqx
import numpy as np
from _util import output_dir, write_json

from jaxveh.analysis import car_preview, preview_distance_sensitivity, preview_report
from jaxveh.plots import plot_car_preview, save
from jaxveh.vehicle import load_car

MUS = np.logspace(-1, 1, 9)


def main():
    out = output_dir("fig_7_10", __doc__)
    car = load_car(modes=6)
    report = preview_report(car, 100.0, mus=MUS)
    lp, dlp = preview_distance_sensitivity(car, 0)
    h = 1e-3
    moved = [eqx.tree_at(lambda c: c.params.chassis.stiffness_scale, car,
                         car.params.chassis.stiffness_scale.at[0].set(1.0 + s * h)) for s in (1.0, -1.0)]
    fd = (float(car_preview(moved[0]).lp) - float(car_preview(moved[1]).lp)) / (2 * h)
    report["dlp_dmu1_m"] = {"forward_mode": float(dlp), "central_difference": fd}
    save(plot_car_preview(report), out / "fig_7_10.png")
    write_json(report, out / "fig_7_10.json")
    c3 = report["chapter_3"]
    print(f"Lp at 100 km/h: flexible {report['flexible']['preview_distance_m']:.2f} m, rigid "
          f"{report['rigid']['preview_distance_m']:.2f} m; chapter 3: flexible "
          f"{c3['flexible']['preview_distance_m']:.2f} m, rigid {c3['rigid']['preview_distance_m']:.2f} m")
    print("Lp by number of modes:", ", ".join(f"{x:.2f}" for x in report["preview_distance_by_modes_m"]))
    for k, row in enumerate(report["preview_distance_vs_mu_m"]):
        print(f"  mode {k + 1}: Lp(µ) = " + ", ".join(f"{x:.2f}" for x in row))
    print(f"d Lp / d mu_1 = {dlp:.5f} m (central differences {fd:.5f} m)")


if __name__ == "__main__":
    main()
