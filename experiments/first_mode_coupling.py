"""Where the first chassis mode goes when it couples (docs/analysis.md, "Deviation from the
thesis"): the 6-mode car linearised about straight running, its modes between 10 and 45 Hz
with their kinetic-energy shares, for the shipped car and for variants that each change one
path between the chassis and the wheels' spin: the wheels' spin inertia × 10, the tyres'
longitudinal relaxation length / 10, and the speed (100 km/h against 50). A mode whose
frequency moves with them is a wheel-spin / longitudinal-tyre mode the chassis takes part
in. For the shipped car and the heavy wheels also the coupling root locus's first chassis
mode (followed by MAC from the free-free 39 Hz mode at coupling 0, as Fig. 7.7a), and the
mode with the largest share of chassis modes 1 and 2 at coupling 1. Writes
first_mode_coupling.json (default results/first_mode_coupling)."""

import numpy as np
from _util import output_dir, write_json

from jaxveh.analysis import kinetic_energy_shares, linearise, modes, root_locus_report
from jaxveh.params import get_at
from jaxveh.vehicle import load_car, with_params

BAND_HZ = (10.0, 45.0)
SPIN = ("vehicle.unsprung_front.wheel_spin_inertia", "vehicle.unsprung_rear.wheel_spin_inertia")


def _variants(car):
    p = car.params
    return {
        "shipped, 50 km/h": (car, 50.0),
        "wheel spin inertia x 10": (with_params(car, {k: 10.0 * float(get_at(p, k)) for k in SPIN}), 50.0),
        "longitudinal relaxation length / 10": (
            with_params(car, {"vehicle.tyre.sigma_kappa": 0.1 * float(p.vehicle.tyre.sigma_kappa)}), 50.0),
        "shipped, 100 km/h": (car, 100.0),
    }


def _band(car, speed_kmh):
    lam, vec = modes(linearise(car, speed_kmh / 3.6))
    rows = []
    for k in range(lam.shape[0]):
        f = lam[k].imag / (2.0 * np.pi)
        if not BAND_HZ[0] <= f <= BAND_HZ[1]:
            continue
        shares = kinetic_energy_shares(car, vec[:, k])
        top = sorted(shares.items(), key=lambda kv: -kv[1])[:4]
        rows.append({"frequency_hz": float(f), "damping_ratio": float(-lam[k].real / abs(lam[k])),
                     "natural_frequency_hz": float(abs(lam[k]) / (2.0 * np.pi)),
                     "chassis_1_2_share": float(shares.get("chassis mode 1", 0.0) + shares.get("chassis mode 2", 0.0)),
                     "energy": {name: round(float(x), 3) for name, x in top}})
    return rows


def _tracked(car):
    """The coupling root locus's first chassis mode at coupling 0 and 1 (Hz, label)."""
    return root_locus_report(car, "coupling")["first_chassis_mode_hz"]


def main():
    out = output_dir("first_mode_coupling", __doc__)
    car = load_car(modes=6)
    report = {}
    for label, (variant, speed) in _variants(car).items():
        rows = _band(variant, speed)
        report[label] = {"modes": rows}
        print(label)
        for row in rows:
            energy = ", ".join(f"{k} {v:.2f}" for k, v in row["energy"].items())
            print(f"  {row['frequency_hz']:6.2f} Hz (natural {row['natural_frequency_hz']:6.2f})  zeta "
                  f"{row['damping_ratio']:.3f}  {energy}")
        top = max(rows, key=lambda r: r["chassis_1_2_share"])
        print(f"  most chassis modes 1+2 ({top['chassis_1_2_share']:.2f}): {top['frequency_hz']:.2f} Hz, zeta "
              f"{top['damping_ratio']:.3f}")
        if label in ("shipped, 50 km/h", "wheel spin inertia x 10"):
            report[label]["tracked_first_chassis_mode"] = tracked = _tracked(variant)
            print(f"  tracked first chassis mode: {tracked}")
    write_json(report, out / "first_mode_coupling.json")


if __name__ == "__main__":
    main()
