"""Mesh convergence of free-free tube bending frequencies: lumped vs consistent mass.

The lumped mass matrix gives every node the rotary inertia of its half elements
(``rho I L/2`` about the transverse axes plus the O(h^2) rod term), so as the mesh is
refined it converges to a **Rayleigh** beam (Euler-Bernoulli stiffness + rotary inertia
``rho I``). The consistent mass matrix has no bending rotary inertia and converges to the
**Euler-Bernoulli** beam. This script solves both closed forms (free-free characteristic
equations) and prints the relative error of every bending frequency for several meshes.

    .venv/bin/python experiments/fe_mesh_convergence.py [--elements 15 30 60 120]

Reference tube (as tests/test_fe_beam.py): L = 1.2 m, D = 30 mm, t = 2 mm steel
(E = 210 GPa, G = 80.8 GPa, rho = 7850 kg/m^3).
"""

import argparse
import dataclasses

import numpy as np
from scipy.optimize import brentq

import jaxveh.fe as fe

E, G, RHO = 210e9, 80.8e9, 7850.0
D, T, LENGTH = 0.03, 0.002, 1.2


def tube_properties(d=D, t=T):
    ro, ri = d / 2, d / 2 - t
    return np.pi * (ro**2 - ri**2), np.pi / 4 * (ro**4 - ri**4)


def euler_bernoulli_hz(n_modes, length=LENGTH, e=E, rho=RHO, d=D, t=T):
    """Free-free Euler-Bernoulli bending frequencies (Hz): cos(x) cosh(x) = 1."""
    area, i = tube_properties(d, t)
    roots = [brentq(lambda x: np.cos(x) * np.cosh(x) - 1.0, (k + 0.05) * np.pi, (k + 0.95) * np.pi)
             for k in range(1, n_modes + 1)]
    return np.asarray(roots) ** 2 / (2 * np.pi * length**2) * np.sqrt(e * i / (rho * area))


def rayleigh_hz(n_modes, length=LENGTH, e=E, rho=RHO, d=D, t=T):
    """Free-free Rayleigh-beam bending frequencies (Hz).

    ``E I X'''' + rho I w^2 X'' - rho A w^2 X = 0``, free ends ``X'' = 0`` and
    ``X''' + (rho w^2 / E) X' = 0``. Symmetric (cosh, cos) and antisymmetric (sinh, sin)
    modes about the centre give 2x2 determinants whose sign changes are bracketed and
    solved with Brent's method.
    """
    area, i = tube_properties(d, t)
    h = 0.5 * length

    def det(w, symmetric):
        a = rho * w**2 / e
        b = rho * area * w**2 / (e * i)
        root = np.sqrt(a * a + 4 * b)
        al, be = np.sqrt(0.5 * (root - a)), np.sqrt(0.5 * (root + a))
        ch, sh = np.cosh(al * h), np.sinh(al * h)
        if symmetric:
            m = [[al**2 * ch, -(be**2) * np.cos(be * h)], [(al**3 + a * al) * sh, (be**3 - a * be) * np.sin(be * h)]]
        else:
            m = [[al**2 * sh, -(be**2) * np.sin(be * h)], [(al**3 + a * al) * ch, (a * be - be**3) * np.cos(be * h)]]
        return np.linalg.det(np.asarray(m)) / ch

    w_eb = 2 * np.pi * euler_bernoulli_hz(n_modes + 2, length, e, rho, d, t)
    grid = np.linspace(0.5 * w_eb[0], 1.05 * w_eb[-1], 20000)
    roots = []
    for symmetric in (True, False):
        v = np.asarray([det(w, symmetric) for w in grid])
        for k in np.nonzero(np.sign(v[:-1]) != np.sign(v[1:]))[0]:
            roots.append(brentq(det, grid[k], grid[k + 1], args=(symmetric,)))
    return np.sort(np.asarray(roots))[:n_modes] / (2 * np.pi)


def bending_frequencies(n_elements, lumped, n_bending):
    """FE bending frequencies (Hz) of the free-free tube, one of each equal y/z pair."""
    frame = dataclasses.replace(fe.straight_tube_frame(LENGTH, n_elements, D, T, E, G, RHO), lumped_mass=lumped)
    K, M = fe.assemble(frame)
    f, phi = fe.free_free_modes(K, M, 2 * n_bending + 6)
    f, phi = np.asarray(f), np.asarray(phi).reshape(-1, 6, f.shape[0])
    # bending modes move the nodes along y or z, axial/torsion modes do not
    lateral = np.sum(phi[:, 1:3, :] ** 2, axis=(0, 1)) > 0.5 * np.sum(phi[:, :3, :] ** 2, axis=(0, 1))
    return f[lateral][0::2][:n_bending]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--elements", type=int, nargs="+", default=[15, 30, 60, 120])
    ap.add_argument("--modes", type=int, default=4)
    args = ap.parse_args()
    eb, ray = euler_bernoulli_hz(args.modes), rayleigh_hz(args.modes)
    print("mode  Euler-Bernoulli Hz  Rayleigh Hz  (Rayleigh - EB)/EB")
    for k in range(args.modes):
        print(f"{k + 1:4d} {eb[k]:19.3f} {ray[k]:12.3f} {100 * (ray[k] / eb[k] - 1):+10.3f} %")
    for n in args.elements:
        lumped = bending_frequencies(n, True, args.modes)
        consistent = bending_frequencies(n, False, args.modes)
        print(f"\n{n} elements: relative errors (%)")
        print("mode  lumped vs EB  lumped vs Rayleigh  consistent vs EB")
        for k in range(args.modes):
            print(f"{k + 1:4d} {100 * (lumped[k] / eb[k] - 1):+13.3f} {100 * (lumped[k] / ray[k] - 1):+19.4f} "
                  f"{100 * (consistent[k] / eb[k] - 1):+17.5f}")


if __name__ == "__main__":
    main()
