"""Input validation on the FE design path: named ParameterErrors for concrete values,
run-time errors (never NaN) for traced values inside jit/grad."""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from test_fe_reduction import box_frame

import jaxveh.fe as fe
from jaxveh._core import ParameterError

E, G, RHO = 210e9, 80.8e9, 7850.0


@pytest.fixture(scope="module")
def box():
    return box_frame()


@pytest.fixture(scope="module")
def beam():
    return fe.straight_beam_body(n_modes=3, n_elements=6)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: fe.CircularTube(0.03, 0.0), r"CircularTube.thickness must lie in \(0, inf\).*got 0"),
        (lambda: fe.CircularTube(0.03, 0.016), r"CircularTube.thickness must lie in \(0, diameter/2\].*0.016"),
        (lambda: fe.CircularTube(0.0, 0.001), r"CircularTube.diameter must lie in \(0, inf\)"),
        (lambda: fe.CircularTube(float("nan"), 0.001), r"CircularTube.diameter must lie in \(0, inf\).*nan"),
        (lambda: fe.CircularTube(float("inf"), 0.001), r"CircularTube.diameter must lie in \(0, inf\)"),
        (lambda: fe.RectangularTube(-0.04, 0.02, 0.001), r"RectangularTube.width must lie in \(0, inf\)"),
        (lambda: fe.RectangularTube(0.04, 0.0, 0.001), r"RectangularTube.height must lie in \(0, inf\)"),
        (lambda: fe.RectangularTube(0.04, 0.02, -1e-3), r"RectangularTube.thickness must lie in \(0, inf\)"),
        (
            lambda: fe.RectangularTube(0.04, 0.02, 0.01),
            r"RectangularTube.thickness must lie in \(0, min\(width, height\)/2\)",
        ),
        (lambda: fe.Material(0.0, G, RHO), r"Material.youngs_modulus must lie in \(0, inf\)"),
        (lambda: fe.Material(E, -1.0, RHO), r"Material.shear_modulus must lie in \(0, inf\)"),
        (lambda: fe.Material(E, G, 0.0), r"Material.density must lie in \(0, inf\)"),
        (lambda: fe.Material(E, 60e9, RHO), r"Poisson's ratio E/\(2G\) - 1 must lie in \(-1, 0.5\).*E = 2.1e\+11"),
        (lambda: fe.Material.from_poisson(E, 0.5, RHO), r"Material.poisson_ratio must lie in \(-1, 0.5\)"),
        (lambda: fe.Material.from_poisson(E, -1.0, RHO), r"Material.poisson_ratio must lie in \(-1, 0.5\)"),
        (lambda: fe.straight_tube_frame(1.0, 4, 0.03, 0.0), r"CircularTube.thickness must lie in \(0, inf\)"),
        (lambda: fe.straight_tube_frame(1.0, 4, 0.03, 0.02), r"CircularTube.thickness must lie in \(0, diameter/2\]"),
        (lambda: fe.straight_tube_frame(0.0, 4), r"length = 0.0 m is out of range"),
        (lambda: fe.straight_tube_frame(1.0, 4, density=-1.0), r"Material.density must lie in \(0, inf\)"),
        (lambda: fe.straight_beam_body(n_modes=0), r"n_modes = 0 is out of range"),
        (
            lambda: fe.straight_beam_body(n_modes=100, n_elements=4),
            r"n_modes = 100 is out of range.*allowed 1 <= n_modes <= 24",
        ),
        (lambda: fe.straight_beam_body(n_modes=2, damping_ratio=1.0), r"damping_ratio must lie in \[0, 1\)"),
        (lambda: fe.straight_beam_body(n_modes=2, damping_ratio=-0.01), r"damping_ratio must lie in \[0, 1\)"),
        (lambda: fe.straight_beam_body(n_modes=2, damping_ratio=[0.02, 0.03, 0.04]), "one value per mode"),
        (lambda: fe.straight_beam_body(n_modes=2, alpha=-1.0), r"alpha \(Rayleigh .*\) must lie in \[0, inf\)"),
        (lambda: fe.straight_beam_body(n_modes=2, beta=-0.01), r"beta \(Rayleigh .*\) must lie in \[0, inf\)"),
        (lambda: fe.modal_damping_ratios(jnp.asarray([0.0, 10.0])), r"frequencies_hz must lie in \(0, inf\)"),
    ],
)
def test_bad_design_values_give_named_errors(make, message):
    with pytest.raises(ParameterError, match=message):
        make()


def test_solid_bar_and_thick_walls_are_allowed():
    """t = D/2 is a solid circular bar (J = 2I exact); walls just below the limits pass."""
    s = fe.CircularTube(0.03, 0.015).properties()
    np.testing.assert_allclose(s.torsion, np.pi * 0.03**4 / 32, rtol=1e-14)
    assert np.isfinite(float(fe.RectangularTube(0.04, 0.02, 0.0099).properties().torsion))
    nu = fe.Material.from_poisson(E, 0.3, RHO).poisson_ratio
    np.testing.assert_allclose(nu, 0.3, rtol=1e-14)


def test_with_sections_checks_count_type_and_values(box):
    good = [fe.CircularTube(0.025, 0.0016), fe.RectangularTube(0.02, 0.03, 0.0012)]
    assert fe.with_sections(box, good).sections[0].diameter == 0.025
    with pytest.raises(ParameterError, match=r"the frame has 2 sections \['tube', 'thin'\], got 1"):
        fe.with_sections(box, good[:1])
    with pytest.raises(ParameterError, match="section 'thin' must be a CircularTube or RectangularTube, got str"):
        fe.with_sections(box, [good[0], "thin"])
    # a section edited past its constructor (tree_at) is re-checked
    bad = eqx.tree_at(lambda s: s.thickness, good[0], 0.0)
    with pytest.raises(ParameterError, match=r"CircularTube.thickness must lie in \(0, inf\)"):
        fe.with_sections(box, [bad, good[1]])
    with pytest.raises(ParameterError, match=r"CircularTube.thickness must lie in \(0, diameter/2\]"):
        eqx.tree_at(lambda s: s.thickness, good[0], 0.02).properties()


def test_frame_file_material_with_poisson_ratio_above_half(box):
    table = {
        "materials": {"steel": {"E": 210.0, "G": 60.0, "density": 7850.0}},
        "sections": {"tube": {"shape": "circular", "diameter": 25.0, "thickness": 12.5}},
        "nodes": {"a": [0.0, 0.0, 0.0], "b": [1000.0, 0.0, 0.0]},
        "members": [{"nodes": ["a", "b"], "section": "tube"}],
    }
    with pytest.raises(ParameterError, match=r"f.toml \[materials.steel\]: Material: Poisson's ratio"):
        fe.frame_from_dict(table, "f.toml")
    table["materials"]["steel"]["G"] = 80.0  # and t = D/2 exactly (solid bar) survives mm -> m
    assert fe.frame_from_dict(table, "f.toml").sections[0].thickness == 0.0125


def test_modal_body_fields_are_checked(beam):
    mu = eqx.tree_at(lambda b: b.stiffness_scale, beam, jnp.asarray([1.0, 0.0, 2.0]))
    with pytest.raises(ParameterError, match=r"ModalBody.stiffness_scale must lie in \(0, inf\).*got 0"):
        mu.stiffness_matrix()
    with pytest.raises(ParameterError, match=r"ModalBody.damping_ratio must lie in \[0, 1\)"):
        eqx.tree_at(lambda b: b.damping_ratio, beam, jnp.full(3, 1.5)).damping_matrix()
    with pytest.raises(ParameterError, match=r"ModalBody.alpha must lie in \[0, inf\)"):
        eqx.tree_at(lambda b: b.alpha, beam, jnp.asarray(-1.0)).damping_matrix()
    with pytest.raises(ParameterError, match=r"ModalBody.beta must lie in \[0, inf\)"):
        eqx.tree_at(lambda b: b.beta, beam, jnp.asarray(-1.0)).elastic_forces(jnp.zeros(3), jnp.zeros(3))
    # construction with concrete values checks shapes and ranges
    fields = {f: getattr(beam, f) for f in ("invariants", "Ke", "alpha", "beta", "damping_ratio", "stiffness_scale",
                                            "point_names", "point_xyz", "point_phi_translation", "point_phi_rotation")}
    with pytest.raises(ParameterError, match=r"ModalBody.stiffness_scale must lie in \(0, inf\)"):
        fe.ModalBody(**{**fields, "stiffness_scale": -jnp.ones(3)})
    with pytest.raises(ParameterError, match=r"ModalBody.damping_ratio must have shape \(3,\)"):
        fe.ModalBody(**{**fields, "damping_ratio": jnp.zeros(2)})


# --- traced values: run-time errors, never NaN -------------------------------------------


def _sized(frame, d, t):
    return fe.with_sections(frame, [fe.CircularTube(d, t), frame.sections[1]])


def test_traced_section_sizes_raise_at_run_time(box):
    mass = jax.jit(lambda t: fe.frame_mass(_sized(box, 0.025, t)))
    assert np.isfinite(float(mass(0.0016)))
    with pytest.raises(Exception, match=r"CircularTube.thickness must lie in \(0, inf\)"):
        mass(0.0).block_until_ready()
    with pytest.raises(Exception, match=r"CircularTube.thickness must lie in \(0, diameter/2\]"):
        mass(0.02).block_until_ready()
    # inside grad of a frequency (an optimiser's step)
    f1 = jax.jit(jax.grad(lambda t: fe.chassis_modes(_sized(box, 0.025, t), 1)[0][0]))
    assert np.isfinite(float(f1(0.0016)))
    with pytest.raises(Exception, match=r"CircularTube.thickness must lie in \(0, diameter/2\]"):
        f1(0.013).block_until_ready()


def test_traced_values_edited_with_tree_at_raise_in_assembly(box):
    """Values put into a frame with eqx.tree_at skip the constructors; assembly checks them."""
    assemble = jax.jit(fe.assemble)
    cases = [
        (lambda f: f.sections[0].thickness, 0.0, r"CircularTube.thickness must lie in \(0, inf\)"),
        (lambda f: f.sections[1].width, -0.02, r"RectangularTube.width must lie in \(0, inf\)"),
        (lambda f: f.materials[0].shear_modulus, 50e9, r"Poisson's ratio E/\(2G\) - 1 must lie in \(-1, 0.5\)"),
        (lambda f: f.materials[0].density, 0.0, r"Material.density must lie in \(0, inf\)"),
        (lambda f: f.node_xyz, box.node_xyz.at[1].set(box.node_xyz[0]), "zero length"),
    ]
    for where, value, message in cases:
        with pytest.raises(Exception, match=message):
            jax.block_until_ready(assemble(eqx.tree_at(where, box, value)))
    torsion = jax.jit(fe.torsion_test)
    with pytest.raises(Exception, match=r"TorsionTest.load must be a non-zero finite force"):
        jax.block_until_ready(torsion(eqx.tree_at(lambda f: f.torsion_test.load, box, 0.0)))
    with_mass = dataclasses.replace(box, mass_nodes=(0,), point_masses=jnp.asarray([-1.0]))
    with pytest.raises(Exception, match=r"Frame.point_masses must lie in \[0, inf\)"):
        jax.block_until_ready(assemble(with_mass))


def test_traced_modal_body_values_raise_at_run_time(beam):
    p, pd = jnp.full(3, 1e-3), jnp.full(3, 0.1)

    def forces(mu, zeta, beta):
        b = eqx.tree_at(lambda b: (b.stiffness_scale, b.damping_ratio, b.beta), beam, (mu, zeta, beta))
        return b.elastic_forces(p, pd)

    f = jax.jit(forces)
    ok = f(jnp.ones(3), jnp.full(3, 0.025), jnp.asarray(0.0))
    assert np.all(np.isfinite(ok))
    with pytest.raises(Exception, match=r"ModalBody.stiffness_scale must lie in \(0, inf\)"):
        f(jnp.asarray([1.0, -0.5, 1.0]), jnp.full(3, 0.025), jnp.asarray(0.0)).block_until_ready()
    with pytest.raises(Exception, match=r"ModalBody.damping_ratio must lie in \[0, 1\)"):
        f(jnp.ones(3), jnp.full(3, 1.0), jnp.asarray(0.0)).block_until_ready()
    with pytest.raises(Exception, match=r"ModalBody.beta must lie in \[0, inf\)"):
        f(jnp.ones(3), jnp.full(3, 0.025), jnp.asarray(-1e-3)).block_until_ready()
    g = jax.jit(jax.grad(lambda mu: jnp.sum(forces(mu, jnp.full(3, 0.025), jnp.asarray(0.0)))))
    assert np.all(np.isfinite(g(jnp.ones(3))))
    with pytest.raises(Exception, match=r"ModalBody.stiffness_scale must lie in \(0, inf\)"):
        g(jnp.zeros(3)).block_until_ready()
