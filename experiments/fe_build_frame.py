"""Generate the shipped FSAE frame TOML (jaxveh/fe/data/fsae_2009_frame.toml).

The frame is laid out around the 32 sprung-side hard points of Appendix B (vehicle frame,
mm): front bulkhead (x = 1300), front box carrying the front suspension, front hoop
(x = 600), cockpit/side-impact structure, main hoop (x = -350) with rear bracing, rear box
carrying the rear suspension and a rear bulkhead (x = -1080). Members ahead of the front
hoop / behind the main hoop get "front_" / "rear_" section groups so the tuning
(experiments/fe_tune_frame.py) can size them separately.

    .venv/bin/python experiments/fe_build_frame.py --sections results/fe_tune_frame/sections.json \
        --point-mass 0.02 --out jaxveh/fe/data/fsae_2009_frame.toml
"""

import argparse
import json

import numpy as np

from jaxveh.params import HARD_POINT_NAMES, SPRUNG_HARD_POINTS, hard_points_vehicle_frame, load_vehicle_data

vd = load_vehicle_data()
hp = hard_points_vehicle_frame(vd)
nodes = {}
for corner in ("front_left", "front_right", "rear_left", "rear_right"):
    for p in SPRUNG_HARD_POINTS:
        nodes[f"{corner}.{p}"] = [round(float(v) * 1e3, 1) for v in np.asarray(hp[corner][HARD_POINT_NAMES.index(p)])]

extra = {  # left side, mm
    "bulkhead_lower": (1300, 180, 150), "bulkhead_upper": (1300, 180, 480),
    "front_hoop_lower": (600, 270, 140), "front_hoop_mid": (600, 275, 345),
    "front_hoop_shoulder": (600, 280, 600), "front_hoop_top": (600, 150, 780),
    "cockpit_lower": (100, 310, 140), "cockpit_mid": (100, 320, 345), "cockpit_upper": (100, 320, 600),
    "main_hoop_lower": (-350, 300, 140), "main_hoop_mid": (-350, 300, 345),
    "main_hoop_shoulder": (-350, 300, 600), "main_hoop_top": (-350, 220, 1150),
    "rear_lower": (-1080, 200, 160), "rear_upper": (-1080, 200, 430),
}
for side, s in (("left", 1), ("right", -1)):
    for n, (x, y, z) in extra.items():
        nodes[f"{n}_{side}"] = [float(x), float(s * y), float(z)]

side_members = [  # (a, b, section)
    # lower rail
    ("bulkhead_lower", "front.B", "rail"), ("front.B", "front.A", "rail"), ("front.A", "front_hoop_lower", "rail"),
    ("front_hoop_lower", "cockpit_lower", "rail"), ("cockpit_lower", "main_hoop_lower", "rail"),
    ("main_hoop_lower", "rear.B", "rail"), ("rear.B", "rear.A", "rail"), ("rear.A", "rear_lower", "rail"),
    # upper rail / side-impact upper member
    ("bulkhead_upper", "front.F", "brace"), ("front.F", "front.L", "rail"), ("front.L", "front.E", "rail"),
    ("front.E", "front_hoop_mid", "rail"), ("front_hoop_mid", "cockpit_mid", "side_impact"),
    ("cockpit_mid", "main_hoop_mid", "side_impact"), ("main_hoop_mid", "rear.F", "rail"),
    ("rear.F", "rear.L", "rail"), ("rear.L", "rear.E", "rail"), ("rear.E", "rear_upper", "rail"),
    # front bulkhead and box
    ("bulkhead_lower", "bulkhead_upper", "bulkhead"), ("bulkhead_upper", "front.P", "brace"),
    ("front.P", "front.Q", "brace"), ("front.P", "front.F", "brace"), ("front.B", "front.F", "brace"),
    ("front.A", "front.E", "brace"), ("front.A", "front.L", "brace"), ("front.Q", "front_hoop_shoulder", "rail"),
    ("front.Q", "front.T", "brace"), ("front.T", "front.E", "brace"), ("front.T", "front_hoop_shoulder", "brace"),
    # front hoop
    ("front_hoop_lower", "front_hoop_mid", "hoop"), ("front_hoop_mid", "front_hoop_shoulder", "hoop"),
    ("front_hoop_shoulder", "front_hoop_top", "hoop"),
    # cockpit side
    ("front_hoop_shoulder", "cockpit_upper", "rail"), ("cockpit_upper", "main_hoop_shoulder", "rail"),
    ("cockpit_lower", "cockpit_mid", "brace"), ("cockpit_mid", "cockpit_upper", "brace"),
    ("front_hoop_lower", "cockpit_mid", "side_impact"), ("cockpit_mid", "main_hoop_lower", "side_impact"),
    # main hoop and bracing
    ("main_hoop_lower", "main_hoop_mid", "hoop"), ("main_hoop_mid", "main_hoop_shoulder", "hoop"),
    ("main_hoop_shoulder", "main_hoop_top", "hoop"), ("main_hoop_top", "rear.Q", "brace"),
    ("rear.Q", "rear_upper", "brace"), ("main_hoop_shoulder", "rear.Q", "brace"),
    # rear box
    ("rear.P", "rear.Q", "brace"), ("rear.P", "rear.F", "brace"), ("rear.B", "rear.F", "brace"),
    ("rear.A", "rear.E", "brace"), ("rear.B", "rear.L", "brace"), ("rear.T", "rear.Q", "brace"),
    ("rear.T", "rear_upper", "brace"), ("rear_lower", "rear_upper", "bulkhead"),
]
cross = [  # left-right members
    ("bulkhead_lower", "bulkhead"), ("bulkhead_upper", "bulkhead"), ("front.B", "cross"), ("front.A", "cross"),
    ("front.T", "cross"), ("front.P", "cross"), ("front_hoop_lower", "cross"), ("front_hoop_top", "hoop"),
    ("main_hoop_lower", "cross"), ("main_hoop_mid", "cross"), ("main_hoop_top", "hoop"), ("rear.B", "cross"),
    ("rear.P", "cross"), ("rear.T", "cross"), ("rear.A", "cross"), ("rear.E", "cross"),
    ("rear_lower", "cross"), ("rear_upper", "cross"),
]
diag = [  # floor / plane diagonals (left a to right b)
    ("bulkhead_lower", "bulkhead_upper", "bulkhead"), ("front_hoop_lower", "cockpit_lower", "cross"),
    ("cockpit_lower", "main_hoop_lower", "cross"), ("front_hoop_mid", "front_hoop_top", "cross"),
    ("main_hoop_lower", "main_hoop_mid", "cross"), ("rear_lower", "rear.A", "cross"),
    ("rear.E", "rear_upper", "cross"), ("rear.B", "main_hoop_lower", "cross"),
    ("rear.B", "rear.A", "cross"), ("rear.P", "rear.E", "cross"), ("main_hoop_mid", "rear.P", "cross"),
]

def nm(n, side):
    if n.startswith("front."):
        return f"front_{side}.{n[6:]}"
    if n.startswith("rear."):
        return f"rear_{side}.{n[5:]}"
    return f"{n}_{side}"

members = []
for side in ("left", "right"):
    for a, b, s in side_members:
        members.append((nm(a, side), nm(b, side), s))
for a, s in cross:
    members.append((nm(a, "left"), nm(a, "right"), s))
for a, b, s in diag:
    members.append((nm(a, "left"), nm(b, "right"), s))

def group(a, b, s):
    if s == "hoop" or s == "side_impact":
        return s
    xa, xb = nodes[a][0], nodes[b][0]
    if min(xa, xb) >= 599.0:
        return "front_" + s
    if max(xa, xb) <= -349.0:
        return "rear_" + s
    return s
members = [(a, b, group(a, b, s)) for a, b, s in members]
for a, b, _ in members:
    assert a in nodes and b in nodes, (a, b)
used = sorted({s for _, _, s in members})
interface = [f"{c}.{p}" for c in ("front_left", "front_right", "rear_left", "rear_right") for p in SPRUNG_HARD_POINTS]

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--sections", default=None, help="JSON {group: [diameter_mm, thickness_mm]}")
ap.add_argument("--point-mass", type=float, default=0.02, help="kg of brackets at each hard point")
ap.add_argument("--out", default="fsae_2009_frame.toml")
args = ap.parse_args()
sections = {
    "hoop": (25.4, 2.4), "side_impact": (25.4, 1.65), "rail": (25.4, 1.65),
    "brace": (25.4, 1.25), "cross": (25.4, 1.25), "bulkhead": (25.4, 1.65),
}
if args.sections:
    sections.update({k: tuple(v) for k, v in json.load(open(args.sections)).items()})
sections = {k: sections.get(k, sections.get(k.split("_", 1)[-1], sections.get("brace"))) for k in used}
out = []
out.append("""# jaxveh chassis FE model: representative FSAE tubular steel space frame
# (2009 University of Surrey car, thesis section 6.2.2). The thesis's Ansys mesh is not
# published; this frame is a documented stand-in (docs/fe.md): front bulkhead, front box
# carrying the front suspension, front hoop, side-impact structure, main hoop with rear
# bracing, and a rear frame carrying the rear suspension and engine. Like the thesis's
# chassis it is not a fully triangulated space frame. Tube gauges were tuned (experiments/
# fe_tune_frame.py) to mass 23.5 kg, torsional stiffness 385 Nm/deg (thesis test) and a
# first free-free mode near 38 Hz (front torsion, Table 6.4).
#
# Units: mm for lengths, GPa for moduli, kg/m3 for density, kg for point masses, N for
# loads. Axes: vehicle frame of Appendix B (origin on the ground below the c.g., x forward,
# y left, z up). The 32 nodes "<corner>.<point>" are the sprung-side suspension hard points
# A, B, E, F, L, P, Q, T of the four corners (Tables B.2-B.3, tracks 1260/1210 mm,
# a + b = 1700 mm; rear points use Table B.3 as given).

[frame]
description = "FSAE 2009 representative space frame"
max_element_length = 330.0   # mm; longer members are split into several beam elements
timoshenko = false
lumped_mass = true
interface = [""" + ", ".join(f'"{n}"' for n in interface) + """]

[materials.steel]             # high-strength (4130-type) steel tube
E = 205.0                     # GPa
G = 80.0                      # GPa
density = 7850.0              # kg/m3
""")
for k, (d, t) in sections.items():
    out.append(f'[sections.{k}]\nshape = "circular"\ndiameter = {d:.3f}   # mm\nthickness = {t:.3f}  # mm\n')
out.append("[nodes]               # mm [x, y, z]")
for n, p in nodes.items():
    out.append(f'"{n}" = [{p[0]:.1f}, {p[1]:.1f}, {p[2]:.1f}]')
out.append("")
for a, b, s in members:
    out.append(f'[[members]]\nnodes = ["{a}", "{b}"]\nsection = "{s}"\n')
out.append("""[point_masses]        # kg: welded brackets, tabs and gussets at the suspension mounts
""" + "\n".join(f'"{n}" = {args.point_mass:.4f}' for n in interface) + """

[torsion_test]        # section 6.2.2: rear supports and front support simply supported
loaded = "front_left.F"
front_support = "front_right.F"
rear_supports = ["rear_left.F", "rear_right.F"]
load = 1000.0         # N, vertical, positive up
""")
open(args.out, "w").write("\n".join(out))
print(f"wrote {args.out}: {len(nodes)} nodes, {len(members)} members")
