"""Thesis Fig. 6.7 (FE model of the chassis), Fig. 6.8 and Table 6.4 (six lowest modes),
plus the torsion test of section 6.2.2, for the shipped FSAE frame (or --frame FILE).

    .venv/bin/python experiments/fig_6_8_modes.py --out results/fig_6_8_modes

Writes frame.png, modes.png, table_6_4.csv and summary.json.
"""

import argparse
import csv
import json
from pathlib import Path

import numpy as np

import jaxveh.fe as fe
from jaxveh.fe._plot import save_frame_and_modes

#: Thesis Table 6.4: natural frequency (Hz) and description of the six lowest modes.
TABLE_6_4 = [
    (38.35, "front torsion"),
    (54.88, "lateral bending"),
    (63.92, "vertical bending"),
    (79.23, "horizontal lozenging"),
    (92.42, "rear lozenging"),
    (103.21, "rear torsion"),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/fig_6_8_modes"))
    ap.add_argument("--frame", type=Path, default=None)
    args = ap.parse_args()
    frame = fe.load_frame(args.frame)
    t = fe.torsion_test(frame)
    f, phi = fe.chassis_modes(frame, 6)
    labels = fe.mode_labels(frame, phi)
    args.out.mkdir(parents=True, exist_ok=True)
    save_frame_and_modes(frame, f, phi, labels, args.out)
    rows = []
    with open(args.out / "table_6_4.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["mode", "thesis_freq_hz", "thesis_description", "jaxveh_freq_hz", "jaxveh_label"])
        for k, ((ft, dt), fj, lj) in enumerate(zip(TABLE_6_4, np.asarray(f), labels)):
            w.writerow([k + 1, ft, dt, round(float(fj), 2), lj])
            rows.append({"mode": k + 1, "thesis_hz": ft, "thesis": dt, "jaxveh_hz": float(fj), "jaxveh": lj})
    summary = {
        "mass_kg": float(t.mass),
        "mass_kg_thesis": 23.5,
        "torsional_stiffness_Nm_per_deg": float(t.stiffness_nm_per_deg),
        "torsional_stiffness_thesis_fe": 385.0,
        "torsional_stiffness_thesis_measured": 360.0,
        "modes": rows,
    }
    (args.out / "summary.json").write_text(json.dumps(summary, indent=2))
    print(f"mass {summary['mass_kg']:.2f} kg (thesis 23.5), torsional stiffness "
          f"{summary['torsional_stiffness_Nm_per_deg']:.1f} Nm/deg (thesis FE 385, measured 360)")
    print(f"{'mode':>4} {'thesis Hz':>10}  {'thesis':<22} {'jaxveh Hz':>10}  jaxveh")
    for r in rows:
        print(f"{r['mode']:4d} {r['thesis_hz']:10.2f}  {r['thesis']:<22} {r['jaxveh_hz']:10.2f}  {r['jaxveh']}")


if __name__ == "__main__":
    main()
