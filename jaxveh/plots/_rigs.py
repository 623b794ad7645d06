"""Kinematic-rig figures in the style of the thesis's Figs. 6.11 (bump) and 6.12 (steering),
and the roll test, drawn from the plain-data reports of :mod:`jaxveh.vehicle`."""

from ._chapter3 import figure

_AXLE_STYLE = {"front": "-", "rear": "--"}


def plot_bump(report: dict, title: str = ""):
    """Bump test: tyre load, camber, toe, track, wheel-centre x and y vs wheel travel, front
    and rear (left wheel)."""
    fig, axes = figure(2, 3, figsize=(11, 6))
    panels = (("fz_n", "tyre vertical load (N)"), ("camber_deg", "camber (deg)"), ("toe_deg", "toe-in (deg)"),
              ("track_mm", "track (mm)"), ("wheel_centre_x_mm", "wheel centre x (mm)"),
              ("wheel_centre_y_mm", "wheel centre y (mm)"))
    for ax, (key, label) in zip(axes.ravel(), panels, strict=True):
        for axle in ("front", "rear"):
            ax.plot(report[axle]["travel_mm"], report[axle][key], _AXLE_STYLE[axle], label=axle)
        ax.set_xlabel("wheel travel (mm, + bump)")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend()
    if title:
        fig.suptitle(title)
    return fig


def plot_steer(report: dict, title: str = ""):
    """Steering test: road-wheel angles, camber, track, scrub radius and Ackermann vs
    steering-wheel angle."""
    fig, axes = figure(2, 3, figsize=(11, 6))
    x, f = report["steering_wheel_deg"], report["front"]
    ax = axes[0, 0]
    ax.plot(x, f["left_deg"], label="left")
    ax.plot(x, f["right_deg"], "--", label="right")
    ax.set_ylabel("road-wheel angle (deg, + left)")
    ax.legend()
    ax = axes[0, 1]
    ax.plot(x, f["left_camber_deg"], label="left")
    ax.plot(x, f["right_camber_deg"], "--", label="right")
    ax.set_ylabel("camber (deg)")
    ax.legend()
    axes[0, 2].plot(x, f["track_mm"])
    axes[0, 2].set_ylabel("track (mm)")
    axes[1, 0].plot(x, f["scrub_radius_mm"])
    axes[1, 0].set_ylabel("scrub radius, left (mm)")
    acker = [(a, v) for a, v in zip(x, f["ackermann_pct"], strict=True) if v is not None]
    axes[1, 1].plot([a for a, _ in acker], [v for _, v in acker], "o-")
    axes[1, 1].set_ylabel("Ackermann (%)")
    axes[1, 2].axis("off")
    for ax in axes.ravel()[:5]:
        ax.set_xlabel("steering-wheel angle (deg)")
        ax.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    return fig


def plot_roll(report: dict, title: str = ""):
    """Roll test: roll camber, roll steer (left wheels) and roll moment per axle vs roll."""
    fig, axes = figure(1, 3, figsize=(11, 3.6))
    x = report["roll_deg"]
    for axle in ("front", "rear"):
        r = report[axle]
        axes[0].plot(x, r["camber_deg"], _AXLE_STYLE[axle], label=axle)
        axes[1].plot(x, r["toe_deg"], _AXLE_STYLE[axle], label=axle)
        k = report["roll_stiffness_nm_per_deg"][axle]
        axes[2].plot(x, r["roll_moment_nm"], _AXLE_STYLE[axle], label=f"{axle} ({k:.0f} Nm/deg)")
    for ax, label in zip(axes, ("camber, left (deg, road)", "toe-in, left (deg)", "roll moment (N m)"), strict=True):
        ax.set_xlabel("chassis roll (deg, + right down)")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.legend()
    if title:
        fig.suptitle(title)
    return fig
