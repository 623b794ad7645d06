"""Three-dimensional two-node beam element: sections, local matrices, transformation.

Each node carries six degrees of freedom ``(ux, uy, uz, rx, ry, rz)`` in the global
frame (m, rad). The element's local frame has ``x`` along the axis from node 1 to node 2,
local ``y`` orthogonal to ``x`` in the plane of ``x`` and the member's orientation vector,
and ``z = x × y``. Euler-Bernoulli bending by default; Timoshenko shear deformation as an
option (shear-flexibility factors ``Φ = 12 E I / (G A_s L²)``, Przemieniecki 1968).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._core import float_field
from ._validate import check_interval, check_positive, check_relation

#: Relative slack on the wall-thickness limits, so that t = D/2 given in mm survives the
#: conversion to m (one rounding of each value, ~1e-16 relative).
WALL_RTOL = 1e-12


#: An orientation vector whose component normal to the member is below this fraction of
#: its length counts as parallel (the frame loader uses the same 1e-6).
ORIENTATION_RTOL = 1e-6


class Material(eqx.Module):
    """Isotropic linear-elastic material.

    Attributes:
        youngs_modulus: E (Pa), > 0.
        shear_modulus: G (Pa), > 0, with Poisson's ratio ``E / (2 G) − 1`` in (−1, 0.5)
            (positive-definite isotropic elasticity), i.e. ``0 < E < 3 G``.
        density: rho (kg/m^3), > 0.

    Concrete values are validated on construction (``ParameterError`` naming the field);
    traced values (inside ``jit``/``grad``) are checked at run time. Use
    :meth:`from_poisson` to give Poisson's ratio instead of G.
    """

    youngs_modulus: Float[Array, ""] = float_field()
    shear_modulus: Float[Array, ""] = float_field()
    density: Float[Array, ""] = float_field()

    def __init__(self, youngs_modulus, shear_modulus, density):
        e = check_positive("Material.youngs_modulus", youngs_modulus, "Pa")
        g = check_positive("Material.shear_modulus", shear_modulus, "Pa")
        self.youngs_modulus = check_relation(
            e,
            lambda xp, E, G: ~(E < 3.0 * G),
            "Material: Poisson's ratio E/(2G) - 1 must lie in (-1, 0.5), i.e. E < 3 G",
            E=e,
            G=g,
        )
        self.shear_modulus = g
        self.density = check_positive("Material.density", density, "kg/m^3")

    @classmethod
    def from_poisson(cls, youngs_modulus, poisson_ratio, density) -> "Material":
        """Material from E (Pa), Poisson's ratio ν in (−1, 0.5) and density (kg/m³):
        ``G = E / (2 (1 + ν))``."""
        nu = check_interval("Material.poisson_ratio", poisson_ratio, low=-1.0, high=0.5, low_open=True, high_open=True)
        e = check_positive("Material.youngs_modulus", youngs_modulus, "Pa")
        return cls(e, e / (2.0 * (1.0 + nu)), density)

    @property
    def poisson_ratio(self) -> Float[Array, ""]:
        """ν = E / (2 G) − 1."""
        return self.youngs_modulus / (2.0 * self.shear_modulus) - 1.0

    def validated(self) -> "Material":
        """The same material with every value checked (run-time checks when traced)."""
        return Material(self.youngs_modulus, self.shear_modulus, self.density)


class SectionProperties(eqx.Module):
    """Cross-section constants of one member (SI units, local member axes).

    Attributes:
        area: A (m^2).
        iy, iz: second moments of area about local y and z (m^4).
        torsion: torsion constant J (m^4).
        shear_area_y, shear_area_z: effective shear areas for shear along local y, z (m^2).
    """

    area: Float[Array, "..."]
    iy: Float[Array, "..."]
    iz: Float[Array, "..."]
    torsion: Float[Array, "..."]
    shear_area_y: Float[Array, "..."]
    shear_area_z: Float[Array, "..."]


def _circular(diameter, thickness):
    d = check_positive("CircularTube.diameter", diameter, "m")
    t = check_positive("CircularTube.thickness", thickness, "m")
    t = check_relation(
        t,
        lambda xp, thickness, diameter: thickness > 0.5 * diameter * (1.0 + WALL_RTOL),
        "CircularTube.thickness must lie in (0, diameter/2] (diameter/2 is a solid bar)",
        thickness=t,
        diameter=d,
    )
    return d, t


def _rectangular(width, height, thickness):
    b = check_positive("RectangularTube.width", width, "m")
    h = check_positive("RectangularTube.height", height, "m")
    t = check_positive("RectangularTube.thickness", thickness, "m")
    t = check_relation(
        t,
        lambda xp, thickness, width, height: thickness >= 0.5 * xp.minimum(width, height) * (1.0 - WALL_RTOL),
        "RectangularTube.thickness must lie in (0, min(width, height)/2)",
        thickness=t,
        width=b,
        height=h,
    )
    return b, h, t


class CircularTube(eqx.Module):
    """Thin- or thick-walled circular tube.

    Attributes:
        diameter: outer diameter D (m), > 0.
        thickness: wall thickness t (m), 0 < t <= D/2 (t = D/2 is a solid bar).

    Validated on construction (concrete values: ``ParameterError``) and again whenever
    :meth:`properties` is evaluated (traced values: a run-time error, never NaN).
    """

    diameter: Float[Array, ""] = float_field()
    thickness: Float[Array, ""] = float_field()

    def __init__(self, diameter, thickness):
        self.diameter, self.thickness = _circular(diameter, thickness)

    def validated(self) -> "CircularTube":
        """The same section with its values checked (run-time checks when traced)."""
        return CircularTube(self.diameter, self.thickness)

    def properties(self) -> SectionProperties:
        """Exact annulus constants; shear area A/2 (thin-walled tube)."""
        d, t = _circular(self.diameter, self.thickness)
        ro = 0.5 * d
        ri = ro - t
        area = jnp.pi * (ro**2 - ri**2)
        i = 0.25 * jnp.pi * (ro**4 - ri**4)
        return SectionProperties(area, i, i, 2.0 * i, 0.5 * area, 0.5 * area)


class RectangularTube(eqx.Module):
    """Rectangular hollow section, walls of uniform thickness.

    Attributes:
        width: outer dimension along local y, b (m), > 0.
        height: outer dimension along local z, h (m), > 0.
        thickness: wall thickness t (m), 0 < t < min(b, h)/2 (the Bredt-Batho torsion
            constant needs a hollow section).

    Validated on construction and in :meth:`properties`, as :class:`CircularTube`.
    """

    width: Float[Array, ""] = float_field()
    height: Float[Array, ""] = float_field()
    thickness: Float[Array, ""] = float_field()

    def __init__(self, width, height, thickness):
        self.width, self.height, self.thickness = _rectangular(width, height, thickness)

    def validated(self) -> "RectangularTube":
        """The same section with its values checked (run-time checks when traced)."""
        return RectangularTube(self.width, self.height, self.thickness)

    def properties(self) -> SectionProperties:
        """Bending constants exact for the hollow rectangle; torsion by Bredt-Batho
        ``J = 4 A_m^2 t / p_m`` on the wall mid-line; shear area of the webs."""
        b, h, t = _rectangular(self.width, self.height, self.thickness)
        bi, hi = b - 2.0 * t, h - 2.0 * t
        area = b * h - bi * hi
        iz = (h * b**3 - hi * bi**3) / 12.0
        iy = (b * h**3 - bi * hi**3) / 12.0
        bm, hm = b - t, h - t
        torsion = 4.0 * (bm * hm) ** 2 * t / (2.0 * (bm + hm))
        return SectionProperties(area, iy, iz, torsion, 2.0 * t * bm, 2.0 * t * hm)


def direction_cosines(
    x1: Float[Array, "3"], x2: Float[Array, "3"], orientation: Float[Array, "3"]
) -> tuple[Float[Array, ""], Float[Array, "3 3"]]:
    """Length (m) and rotation ``R`` (rows: local x, y, z in global axes) of a member.

    ``orientation`` is any global vector not parallel to the member; local y is its
    component orthogonal to the axis.

    Zero-length members (coincident nodes, e.g. moved by an optimiser) and orientation
    vectors parallel to the member are refused (``ParameterError``, or a run-time error
    when traced) instead of giving NaN.
    """
    d = x2 - x1
    length = jnp.sqrt(jnp.sum(d * d))
    length = check_relation(
        length,
        lambda xp, length: ~(length > 0.0),
        "beam element has zero length (coincident nodes) or a non-finite node position",
        length=length,
    )
    ex = d / length
    y = orientation - jnp.dot(orientation, ex) * ex
    ny = jnp.sqrt(jnp.sum(y * y))
    ny = check_relation(
        ny,
        lambda xp, normal, orientation: ~(normal > ORIENTATION_RTOL * xp.sqrt(xp.sum(orientation * orientation))),
        "member orientation vector is parallel to the member (local y undefined)",
        normal=ny,
        orientation=orientation,
    )
    ey = y / ny
    ez = jnp.cross(ex, ey)
    return length, jnp.stack([ex, ey, ez])


def local_stiffness(
    length: Float[Array, ""],
    sec: SectionProperties,
    mat: Material,
    timoshenko: bool = False,
) -> Float[Array, "12 12"]:
    """Local 12x12 stiffness (N/m, N, Nm/rad) of a straight prismatic beam.

    DOF order per node: u, v, w, θx, θy, θz (local axes). Bending in the x-y plane uses
    ``iz``, in the x-z plane ``iy``; Timoshenko shear factors when ``timoshenko``.
    """
    E, G, L = mat.youngs_modulus, mat.shear_modulus, length
    if timoshenko:
        phi_y = 12.0 * E * sec.iz / (G * sec.shear_area_y * L**2)
        phi_z = 12.0 * E * sec.iy / (G * sec.shear_area_z * L**2)
    else:
        phi_y = jnp.zeros_like(L)
        phi_z = jnp.zeros_like(L)
    ea = E * sec.area / L
    gj = G * sec.torsion / L

    def bending(ei, phi):
        c = ei / (L**3 * (1.0 + phi))
        return (
            12.0 * c,
            6.0 * L * c,
            (4.0 + phi) * L**2 * c,
            (2.0 - phi) * L**2 * c,
        )

    a1, b1, c1, d1 = bending(E * sec.iz, phi_y)  # v, θz
    a2, b2, c2, d2 = bending(E * sec.iy, phi_z)  # w, θy
    z = jnp.zeros_like(L)
    rows = [
        [ea, z, z, z, z, z, -ea, z, z, z, z, z],
        [z, a1, z, z, z, b1, z, -a1, z, z, z, b1],
        [z, z, a2, z, -b2, z, z, z, -a2, z, -b2, z],
        [z, z, z, gj, z, z, z, z, z, -gj, z, z],
        [z, z, -b2, z, c2, z, z, z, b2, z, d2, z],
        [z, b1, z, z, z, c1, z, -b1, z, z, z, d1],
        [-ea, z, z, z, z, z, ea, z, z, z, z, z],
        [z, -a1, z, z, z, -b1, z, a1, z, z, z, -b1],
        [z, z, -a2, z, b2, z, z, z, a2, z, b2, z],
        [z, z, z, -gj, z, z, z, z, z, gj, z, z],
        [z, z, -b2, z, d2, z, z, z, b2, z, c2, z],
        [z, b1, z, z, z, d1, z, -b1, z, z, z, c1],
    ]
    return jnp.stack([jnp.stack(r) for r in rows])


def local_consistent_mass(
    length: Float[Array, ""], sec: SectionProperties, mat: Material
) -> Float[Array, "12 12"]:
    """Local 12x12 consistent mass (kg, kg m, kg m^2) of an Euler-Bernoulli beam,
    translational inertia plus torsional rotary inertia ``rho J_p L``."""
    L = length
    m = mat.density * sec.area * L
    jp = mat.density * (sec.iy + sec.iz) * L
    c = m / 420.0
    z = jnp.zeros_like(L)
    a, b, d, e = 156.0 * c, 22.0 * L * c, 54.0 * c, 13.0 * L * c
    f, g = 4.0 * L**2 * c, 3.0 * L**2 * c
    rows = [
        [m / 3, z, z, z, z, z, m / 6, z, z, z, z, z],
        [z, a, z, z, z, b, z, d, z, z, z, -e],
        [z, z, a, z, -b, z, z, z, d, z, e, z],
        [z, z, z, jp / 3, z, z, z, z, z, jp / 6, z, z],
        [z, z, -b, z, f, z, z, z, -e, z, -g, z],
        [z, b, z, z, z, f, z, e, z, z, z, -g],
        [m / 6, z, z, z, z, z, m / 3, z, z, z, z, z],
        [z, d, z, z, z, e, z, a, z, z, z, -b],
        [z, z, d, z, -e, z, z, z, a, z, b, z],
        [z, z, z, jp / 6, z, z, z, z, z, jp / 3, z, z],
        [z, z, e, z, -g, z, z, z, b, z, f, z],
        [z, -e, z, z, z, -g, z, -b, z, z, z, f],
    ]
    return jnp.stack([jnp.stack(r) for r in rows])


def lumped_node_inertia(
    length: Float[Array, ""], sec: SectionProperties, mat: Material
) -> tuple[Float[Array, ""], Float[Array, "3"]]:
    """Mass (kg) and local principal inertia (kg m^2) given to each end node.

    Each node receives the half-member next to it, a uniform bar of length L/2: mass
    ``m/2``; inertia about the node of ``rho J_p L/2`` about the axis and
    ``rho I L/2 + (m/2)(L/2)^2/3`` about the transverse axes.
    """
    half = 0.5 * length
    m = mat.density * sec.area * half
    rod = m * half**2 / 3.0
    inertia = jnp.stack(
        [
            mat.density * (sec.iy + sec.iz) * half,
            mat.density * sec.iy * half + rod,
            mat.density * sec.iz * half + rod,
        ]
    )
    return m, inertia


def transformation(rotation: Float[Array, "3 3"]) -> Float[Array, "12 12"]:
    """Block-diagonal ``T`` with ``u_local = T u_global`` for the 12 element DOF."""
    return jax.scipy.linalg.block_diag(rotation, rotation, rotation, rotation)
