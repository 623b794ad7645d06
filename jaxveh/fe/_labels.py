"""Automatic descriptions of chassis mode shapes (torsion, bending, lozenging).

Post-processing in NumPy (labels are strings, not differentiated). A mode's nodal
translations are fitted, mass-weighted, by displacement patterns whose amplitude varies
along the vehicle as Legendre polynomials ``P_0..P_4`` of the normalised x coordinate:

=====================  ======================================  ==========================
family                  pattern (u_x, u_y, u_z)                  meaning
=====================  ======================================  ==========================
torsion                 (0, −z P_k, y P_k)                       sections rotate about x
lateral bending         (0, P_k, 0)                              sections translate along y
vertical bending        (0, 0, P_k)                              sections translate along z
horizontal lozenging    (y P_k, 0, 0)                            plan-view shear (sides slide)
vertical lozenging      (z P_k, 0, 0)                            side-view shear
axial                   (P_k, 0, 0)                              stretching along x
=====================  ======================================  ==========================

(y, z measured from the centre of mass, in m). The family whose fitted part carries most of
the mode's kinetic energy names the mode; if no family explains at least
:data:`LOCAL_SHARE` of it the mode is "local", followed by the name of the user node
nearest to the largest nodal translation (e.g. ``local (main_hoop_top_left)``). A "front"
or "rear" prefix is added when the elastic strain energy is concentrated in that end: its
x-centroid lies beyond
:data:`REGION_THRESHOLD` of the half length from the middle.
"""

import numpy as np
from numpy.polynomial import legendre

#: Minimum energy share a pattern family must explain for a global label.
LOCAL_SHARE = 0.3
#: Normalised x-centroid of strain energy beyond which a mode is called front / rear.
REGION_THRESHOLD = 0.25
FAMILIES = ("torsion", "lateral bending", "vertical bending", "horizontal lozenging", "vertical lozenging", "axial")


def _pattern_fields(xyz: np.ndarray, mass: np.ndarray, degree: int = 4) -> dict[str, list[np.ndarray]]:
    c = (mass[:, None] * xyz).sum(0) / mass.sum()
    x0, x1 = xyz[:, 0].min(), xyz[:, 0].max()
    X = (2.0 * xyz[:, 0] - x0 - x1) / (x1 - x0)
    y, z = xyz[:, 1] - c[1], xyz[:, 2] - c[2]
    zero = np.zeros_like(X)
    out = {f: [] for f in FAMILIES}
    for k in range(degree + 1):
        P = legendre.legval(X, np.eye(degree + 1)[k])
        out["torsion"].append(np.stack([zero, -z * P, y * P], 1))
        out["lateral bending"].append(np.stack([zero, P, zero], 1))
        out["vertical bending"].append(np.stack([zero, zero, P], 1))
        out["horizontal lozenging"].append(np.stack([y * P, zero, zero], 1))
        out["vertical lozenging"].append(np.stack([z * P, zero, zero], 1))
        out["axial"].append(np.stack([P, zero, zero], 1))
    return out


def family_shares(xyz: np.ndarray, mass: np.ndarray, u: np.ndarray) -> dict[str, float]:
    """Kinetic-energy share of each pattern family in translation field ``u`` (n, 3)."""
    fields = _pattern_fields(xyz, mass)
    names, cols = [], []
    for fam, fl in fields.items():
        for f in fl:
            names.append(fam)
            cols.append(f.reshape(-1))
    B = np.stack(cols, 1)
    w = np.sqrt(np.repeat(mass, 3))
    coef, *_ = np.linalg.lstsq(w[:, None] * B, w * u.reshape(-1), rcond=None)
    total = np.sum(w**2 * u.reshape(-1) ** 2)
    shares = {}
    for fam in FAMILIES:
        sel = np.asarray([n == fam for n in names])
        part = B[:, sel] @ coef[sel]
        shares[fam] = float(np.sum(w**2 * part**2) / total)
    return shares


def label_mode(
    xyz: np.ndarray,
    mass: np.ndarray,
    u: np.ndarray,
    element_energy: np.ndarray,
    element_x: np.ndarray,
    node_names: tuple[str, ...] = (),
) -> str:
    """Description of one mode.

    Args:
        xyz: node positions (m), (n, 3); x along the vehicle.
        mass: nodal masses (kg), (n,).
        u: nodal translations of the mode, (n, 3).
        element_energy: strain energy of every element in the mode (J), (e,).
        element_x: x coordinate of every element centre (m), (e,).
        node_names: names of the first ``len(node_names)`` nodes (the user nodes), used
            to locate local modes.
    """
    shares = family_shares(xyz, mass, u)
    fam = max(shares, key=shares.get)
    if shares[fam] < LOCAL_SHARE:
        if not node_names:
            return "local"
        peak = xyz[np.argmax(np.sum(u * u, axis=1))]
        near = np.argmin(np.sum((xyz[: len(node_names)] - peak) ** 2, axis=1))
        return f"local ({node_names[near]})"
    x0, x1 = xyz[:, 0].min(), xyz[:, 0].max()
    xe = (2.0 * np.sum(element_energy * element_x) / np.sum(element_energy) - x0 - x1) / (x1 - x0)
    if xe > REGION_THRESHOLD:
        return f"front {fam}"
    if xe < -REGION_THRESHOLD:
        return f"rear {fam}"
    return fam
