"""Matplotlib figures of a frame (thesis Fig. 6.7) and of its mode shapes (Fig. 6.8)."""

from pathlib import Path

import numpy as np

from ._assembly import frame_mesh, mesh_xyz
from ._frame import Frame


def _axes_equal(ax, xyz):
    lo, hi = xyz.min(0), xyz.max(0)
    c, r = 0.5 * (lo + hi), 0.5 * (hi - lo).max()
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.view_init(elev=25, azim=-130)


def plot_frame(frame: Frame, ax) -> None:
    """Draw the beam elements, nodes and the interface (hard-point) nodes on a 3D axis."""
    xyz = np.asarray(mesh_xyz(frame))
    for a, b in frame_mesh(frame).elements:
        ax.plot(*xyz[[a, b]].T, color="0.3", lw=1.0)
    ax.scatter(*xyz.T, s=4, color="0.3")
    if frame.interface:
        hp = xyz[[frame.node_index(n) for n in frame.interface]]
        ax.scatter(*hp.T, s=18, color="tab:red", label="suspension hard points")
        ax.legend(loc="upper left", fontsize=8)
    _axes_equal(ax, xyz)


def plot_mode(frame: Frame, mode: np.ndarray, ax, title: str, scale: float = 0.12) -> None:
    """Draw the undeformed frame (grey) and the mode shape scaled so the largest nodal
    translation is ``scale`` m, coloured by translation magnitude (blue min, red max)."""
    import matplotlib.pyplot as plt

    xyz = np.asarray(mesh_xyz(frame))
    u = np.asarray(mode).reshape(-1, 6)[:, :3]
    mag = np.linalg.norm(u, axis=1)
    d = xyz + scale * u / mag.max()
    cmap = plt.get_cmap("jet")
    for a, b in frame_mesh(frame).elements:
        ax.plot(*xyz[[a, b]].T, color="0.85", lw=0.6)
        ax.plot(*d[[a, b]].T, color=cmap(0.5 * (mag[a] + mag[b]) / mag.max()), lw=1.4)
    _axes_equal(ax, xyz)
    ax.set_title(title, fontsize=9)


def save_frame_and_modes(frame: Frame, freqs, modes, labels, out: Path) -> list[Path]:
    """Write ``frame.png`` (Fig. 6.7) and ``modes.png`` (Fig. 6.8, up to six modes)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    fig = plt.figure(figsize=(7, 6))
    ax = fig.add_subplot(projection="3d")
    plot_frame(frame, ax)
    ax.set_title("Finite element model of the chassis (cf. thesis Fig. 6.7)")
    p1 = out / "frame.png"
    fig.savefig(p1, dpi=130, bbox_inches="tight")
    plt.close(fig)
    n = min(6, modes.shape[1])
    fig = plt.figure(figsize=(12, 8))
    for k in range(n):
        ax = fig.add_subplot(2, 3, k + 1, projection="3d")
        plot_mode(frame, np.asarray(modes[:, k]), ax, f"Mode {k + 1}, {float(freqs[k]):.2f} Hz\n{labels[k]}")
    fig.suptitle("Lowest free-free modes of the chassis (cf. thesis Fig. 6.8); colour: |u| min (blue) to max (red)")
    p2 = out / "modes.png"
    fig.savefig(p2, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return [p1, p2]
