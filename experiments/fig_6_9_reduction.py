"""Thesis Fig. 6.9: modal truncation vs orthogonalised Craig-Bampton (32 hard points as
interface) for the first 20 modes: (a) NRFD per mode, (b) MAC matrix.

    .venv/bin/python experiments/fig_6_9_reduction.py --out results/fig_6_9_reduction
"""

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import jaxveh.fe as fe


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/fig_6_9_reduction"))
    ap.add_argument("--frame", type=Path, default=None)
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--n-fixed", type=int, nargs="+", default=[5, 20, 60])
    args = ap.parse_args()
    frame = fe.load_frame(args.frame)
    args.out.mkdir(parents=True, exist_ok=True)
    results = {k: fe.compare_reductions(frame, args.n, k) for k in args.n_fixed}
    modes = np.arange(1, args.n + 1)

    fig = plt.figure(figsize=(12, 4.8))
    ax = fig.add_subplot(1, 2, 1)
    for k, c in results.items():
        ax.semilogy(modes, np.maximum(np.asarray(c["nrfd"]), 1e-12), "o-", ms=4, label=f"{k} fixed-interface modes")
    ax.set_xlabel("Mode")
    ax.set_ylabel("NRFD")
    ax.set_ylim(1e-6, 1)
    ax.set_xlim(0, args.n + 1)
    ax.set_xticks(range(0, args.n + 1, 5))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("(a) Normalised relative frequency difference")
    ref = results[60 if 60 in results else args.n_fixed[-1]]
    ax = fig.add_subplot(1, 2, 2, projection="3d")
    m = np.asarray(ref["mac"])
    X, Y = np.meshgrid(modes, modes, indexing="ij")
    ax.bar3d(X.ravel() - 0.4, Y.ravel() - 0.4, 0 * X.ravel(), 0.8, 0.8, m.ravel(), shade=True,
             color=plt.get_cmap("viridis")(m.ravel()))
    ax.set_xlabel("Mode FEA")
    ax.set_ylabel("Mode CMS")
    ax.set_zlabel("MAC")
    ax.set_title("(b) Modal assurance criterion (60 fixed-interface modes)")
    ax.set_xticks([1, 5, 10, 15, 20])
    ax.set_yticks([1, 5, 10, 15, 20])
    fig.tight_layout()
    fig.savefig(args.out / "fig_6_9.png", dpi=130)
    out = {
        str(k): {
            "freq_truncation_hz": np.asarray(c["freq_truncation_hz"]).tolist(),
            "freq_craig_bampton_hz": np.asarray(c["freq_craig_bampton_hz"]).tolist(),
            "nrfd": np.asarray(c["nrfd"]).tolist(),
            "mac_diagonal": np.asarray(c["mac_diagonal"]).tolist(),
        }
        for k, c in results.items()
    }
    (args.out / "fig_6_9.json").write_text(json.dumps(out, indent=2))
    for k, c in out.items():
        nr, md = np.asarray(c["nrfd"]), np.asarray(c["mac_diagonal"])
        print(f"n_fixed {k:>3}: NRFD max modes 1-10 {nr[:10].max():.2e}, 11-20 {nr[10:].max():.2e}; "
              f"MAC diag min 1-10 {md[:10].min():.3f}, 11-20 {md[10:].min():.3f}")


if __name__ == "__main__":
    main()
