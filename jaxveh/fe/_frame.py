"""Frame description: nodes, members, sections, materials, point masses, torsion test.

A :class:`Frame` is an Equinox pytree. Numbers a designer may differentiate (node
coordinates, section sizes, material constants, point masses, test load) are float64
leaves; topology (names, connectivity, section and material assignment, subdivision) is
static. :func:`load_frame` reads the TOML format documented in ``docs/fe.md`` and validates
it; :func:`frame_from_dict` does the same for an already-parsed table.
"""

import math
from collections import deque
from pathlib import Path

import equinox as eqx
import numpy as np
from jaxtyping import Array, Float

from .._core import ParameterError, check_x64, float_field, read_toml
from ._beam import CircularTube, Material, RectangularTube

Section = CircularTube | RectangularTube


class TorsionTest(eqx.Module):
    """Static torsion test set-up (section 6.2.2 of the thesis).

    ``rear_supports`` (two nodes) and ``front_support`` are simply supported, a vertical
    ``load`` (N, positive up) acts on ``loaded``. Supports restrain translations only, in
    a statically determinate pattern (first rear support: x, y, z; second: x, z; front
    support: z), so no support reaction other than the vertical ones is loaded.
    """

    loaded: str = eqx.field(static=True)
    front_support: str = eqx.field(static=True)
    rear_supports: tuple[str, str] = eqx.field(static=True)
    load: Float[Array, ""] = float_field()


class Frame(eqx.Module):
    """A beam space frame.

    Attributes:
        node_names: names of the user nodes (static).
        node_xyz: node positions (m), shape (n_nodes, 3), in the frame's reference axes
            (for the shipped chassis the vehicle frame: x forward, y left, z up, origin on
            the ground below the c.g.).
        member_nodes: (i, j) node indices of every member (static).
        member_section: section index of every member (static).
        member_material: material index of every member (static).
        member_divisions: number of beam elements each member is split into (static).
        member_orientation: reference vector per member fixing local y (unit-free),
            shape (n_members, 3).
        section_names, sections: named cross sections (design variables).
        material_names, materials: named materials.
        mass_nodes: node index of each non-structural point mass (static).
        point_masses: point masses (kg), shape (n_masses,).
        interface: names of the Craig-Bampton interface / hard-point nodes (static).
        torsion_test: the torsion test set-up, or ``None``.
        timoshenko: include shear deformation (static).
        lumped_mass: lumped (True, thesis) or consistent (False) mass matrix (static).
    """

    node_names: tuple[str, ...] = eqx.field(static=True)
    node_xyz: Float[Array, "n 3"] = float_field()
    member_nodes: tuple[tuple[int, int], ...] = eqx.field(static=True)
    member_section: tuple[int, ...] = eqx.field(static=True)
    member_material: tuple[int, ...] = eqx.field(static=True)
    member_divisions: tuple[int, ...] = eqx.field(static=True)
    member_orientation: Float[Array, "m 3"] = float_field()
    section_names: tuple[str, ...] = eqx.field(static=True)
    sections: tuple[Section, ...]
    material_names: tuple[str, ...] = eqx.field(static=True)
    materials: tuple[Material, ...]
    mass_nodes: tuple[int, ...] = eqx.field(static=True)
    point_masses: Float[Array, " k"] = float_field()
    interface: tuple[str, ...] = eqx.field(static=True)
    torsion_test: TorsionTest | None
    timoshenko: bool = eqx.field(static=True, default=False)
    lumped_mass: bool = eqx.field(static=True, default=True)

    @property
    def n_nodes(self) -> int:
        return len(self.node_names)

    @property
    def n_members(self) -> int:
        return len(self.member_nodes)

    def node_index(self, name: str) -> int:
        """Index of a named node; ``ParameterError`` naming it if absent."""
        try:
            return self.node_names.index(name)
        except ValueError:
            raise ParameterError(f"frame has no node named {name!r}") from None


def default_orientation(xyz: np.ndarray, members) -> np.ndarray:
    """Global z as local-y reference, or global y for members within 25 deg of z."""
    out = np.zeros((len(members), 3))
    for k, (i, j) in enumerate(members):
        d = xyz[j] - xyz[i]
        d = d / np.linalg.norm(d)
        out[k] = (0.0, 1.0, 0.0) if abs(d[2]) > math.cos(math.radians(25.0)) else (0.0, 0.0, 1.0)
    return out


def check_connected(n_nodes: int, members, names, where: str) -> None:
    """Raise ``ParameterError`` listing the nodes not connected to the first node."""
    adj = [[] for _ in range(n_nodes)]
    for i, j in members:
        adj[i].append(j)
        adj[j].append(i)
    seen = {0}
    queue = deque([0])
    while queue:
        k = queue.popleft()
        for n in adj[k]:
            if n not in seen:
                seen.add(n)
                queue.append(n)
    if len(seen) != n_nodes:
        lost = [names[k] for k in range(n_nodes) if k not in seen]
        raise ParameterError(
            f"{where}: the frame is disconnected; node(s) {lost[:10]} are not connected to "
            f"node {names[0]!r}"
        )


def _number(value, name: str, lower: float = 0.0, unit: str = "") -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(f"{name} must be a finite number{(' in ' + unit) if unit else ''}, got {value!r}")
    if value <= lower:
        raise ParameterError(f"{name} = {value:g} {unit} is out of range: allowed > {lower:g} {unit}")
    return float(value)


def _keys(table, allowed, required, where):
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise ParameterError(f"{where}: unknown key(s) {unknown}; allowed keys are {sorted(allowed)}")
    missing = [k for k in required if k not in table]
    if missing:
        raise ParameterError(f"{where}: missing key(s) {missing}")


def _section(name: str, d: dict, where: str) -> Section:
    w = f"{where} [sections.{name}]"
    shape = d.get("shape")
    if shape == "circular":
        _keys(d, ("shape", "diameter", "thickness"), ("diameter", "thickness"), w)
        dia = _number(d["diameter"], f"{w}.diameter", unit="mm")
        t = _number(d["thickness"], f"{w}.thickness", unit="mm")
        if t > 0.5 * dia:
            raise ParameterError(f"{w}.thickness = {t:g} mm is out of range: allowed <= diameter/2 = {dia / 2:g} mm")
        return CircularTube(dia * 1e-3, t * 1e-3)
    if shape == "rectangular":
        _keys(d, ("shape", "width", "height", "thickness"), ("width", "height", "thickness"), w)
        b = _number(d["width"], f"{w}.width", unit="mm")
        h = _number(d["height"], f"{w}.height", unit="mm")
        t = _number(d["thickness"], f"{w}.thickness", unit="mm")
        if t >= 0.5 * min(b, h):
            raise ParameterError(
                f"{w}.thickness = {t:g} mm is out of range: allowed < min(width, height)/2 = {min(b, h) / 2:g} mm"
            )
        return RectangularTube(b * 1e-3, h * 1e-3, t * 1e-3)
    raise ParameterError(f"{w}.shape must be 'circular' or 'rectangular', got {shape!r}")


def _material(name: str, d: dict, where: str) -> Material:
    w = f"{where} [materials.{name}]"
    _keys(d, ("E", "G", "nu", "density"), ("E", "density"), w)
    e = _number(d["E"], f"{w}.E", unit="GPa") * 1e9
    rho = _number(d["density"], f"{w}.density", unit="kg/m3")
    if ("G" in d) == ("nu" in d):
        raise ParameterError(f"{w}: give exactly one of G (GPa) or nu (Poisson's ratio)")
    if "G" in d:
        g = _number(d["G"], f"{w}.G", unit="GPa") * 1e9
    else:
        nu = d["nu"]
        if isinstance(nu, bool) or not isinstance(nu, (int, float)) or not -1.0 < nu < 0.5:
            raise ParameterError(f"{w}.nu = {nu!r} is out of range: allowed -1 < nu < 0.5")
        g = e / (2.0 * (1.0 + nu))
    try:
        return Material(e, g, rho)
    except ParameterError as err:  # e.g. E >= 3 G: Poisson's ratio >= 0.5
        raise ParameterError(f"{w}: {err}") from None


def frame_from_dict(table: dict, where: str = "<dict>") -> Frame:
    """Build and validate a :class:`Frame` from a parsed TOML table (units: mm, GPa, kg).

    Raises:
        ParameterError: unknown/missing sections or keys, duplicate or missing nodes,
            zero-length members, non-positive section sizes or materials, a disconnected
            frame, bad torsion-test nodes. The message names the offending entry.
    """
    check_x64()
    allowed = ("frame", "materials", "sections", "nodes", "members", "point_masses", "torsion_test")
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise ParameterError(f"{where}: unknown section(s) {unknown}; allowed are {list(allowed)}")
    for sec in ("materials", "sections", "nodes", "members"):
        if sec not in table:
            raise ParameterError(f"{where}: missing section [{sec}]")
    opts = table.get("frame", {})
    _keys(opts, ("description", "max_element_length", "timoshenko", "lumped_mass", "interface"), (), f"{where} [frame]")
    max_len = _number(opts.get("max_element_length", 1e9), f"{where} [frame].max_element_length", unit="mm") * 1e-3
    timoshenko = bool(opts.get("timoshenko", False))
    lumped = bool(opts.get("lumped_mass", True))

    material_names = tuple(table["materials"])
    materials = tuple(_material(n, d, where) for n, d in table["materials"].items())
    section_names = tuple(table["sections"])
    sections = tuple(_section(n, d, where) for n, d in table["sections"].items())
    if not sections or not materials:
        raise ParameterError(f"{where}: [sections] and [materials] must each define at least one entry")

    nodes = table["nodes"]
    names = tuple(nodes)
    xyz = []
    for name, p in nodes.items():
        ok = isinstance(p, list) and len(p) == 3 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in p
        )
        if not ok:
            raise ParameterError(f"{where} [nodes].{name} must be a list of 3 numbers [x, y, z] in mm, got {p!r}")
        xyz.append([float(v) * 1e-3 for v in p])
    xyz = np.asarray(xyz)
    if len(names) < 2:
        raise ParameterError(f"{where} [nodes]: a frame needs at least 2 nodes")
    rounded = {}
    for k, name in enumerate(names):
        key = tuple(np.round(xyz[k] * 1e6).astype(int))
        if key in rounded:
            raise ParameterError(
                f"{where} [nodes]: duplicate node position: {name!r} coincides with {rounded[key]!r}"
            )
        rounded[key] = name
    index = {n: k for k, n in enumerate(names)}

    members = table["members"]
    if not isinstance(members, list) or not members:
        raise ParameterError(f"{where}: [[members]] must be a non-empty array of tables")
    m_nodes, m_sec, m_mat, m_div, m_orient = [], [], [], [], []
    pairs = set()
    for k, m in enumerate(members):
        w = f"{where} [[members]] #{k + 1}"
        _keys(m, ("nodes", "section", "material", "orientation", "divisions"), ("nodes", "section"), w)
        ends = m["nodes"]
        if not (isinstance(ends, list) and len(ends) == 2 and all(isinstance(e, str) for e in ends)):
            raise ParameterError(f"{w}.nodes must be a list of two node names, got {ends!r}")
        for e in ends:
            if e not in index:
                raise ParameterError(f"{w}: node {e!r} is not defined in [nodes]")
        i, j = index[ends[0]], index[ends[1]]
        if i == j or np.linalg.norm(xyz[j] - xyz[i]) < 1e-6:
            raise ParameterError(f"{w}: member {ends[0]}-{ends[1]} has zero length")
        if frozenset((i, j)) in pairs:
            raise ParameterError(f"{w}: duplicate member {ends[0]}-{ends[1]}")
        pairs.add(frozenset((i, j)))
        if m["section"] not in section_names:
            raise ParameterError(f"{w}: section {m['section']!r} is not defined; defined are {list(section_names)}")
        mat = m.get("material", material_names[0])
        if mat not in material_names:
            raise ParameterError(f"{w}: material {mat!r} is not defined; defined are {list(material_names)}")
        length = float(np.linalg.norm(xyz[j] - xyz[i]))
        div = m.get("divisions", max(1, math.ceil(length / max_len - 1e-9)))
        if isinstance(div, bool) or not isinstance(div, int) or div < 1:
            raise ParameterError(f"{w}.divisions = {div!r} is out of range: allowed integer >= 1")
        m_nodes.append((i, j))
        m_sec.append(section_names.index(m["section"]))
        m_mat.append(material_names.index(mat))
        m_div.append(div)
        if "orientation" in m:
            o = np.asarray(m["orientation"], dtype=float)
            d = (xyz[j] - xyz[i]) / length
            if o.shape != (3,) or np.linalg.norm(np.cross(o, d)) < 1e-6 * max(np.linalg.norm(o), 1e-300):
                raise ParameterError(
                    f"{w}.orientation must be 3 numbers not parallel to the member, got {m['orientation']!r}"
                )
            m_orient.append(o / np.linalg.norm(o))
        else:
            m_orient.append(default_orientation(xyz, [(i, j)])[0])
    used = {n for ij in m_nodes for n in ij}
    unused = [names[k] for k in range(len(names)) if k not in used]
    if unused:
        raise ParameterError(f"{where} [nodes]: node(s) {unused} belong to no member")
    check_connected(len(names), m_nodes, names, where)

    pm = table.get("point_masses", {})
    mass_nodes, masses = [], []
    for node, value in pm.items():
        if node not in index:
            raise ParameterError(f"{where} [point_masses]: node {node!r} is not defined in [nodes]")
        mass_nodes.append(index[node])
        masses.append(_number(value, f"{where} [point_masses].{node}", unit="kg"))

    interface = opts.get("interface", [])
    for n in interface:
        if n not in index:
            raise ParameterError(f"{where} [frame].interface: node {n!r} is not defined in [nodes]")

    torsion = None
    if "torsion_test" in table:
        t = table["torsion_test"]
        w = f"{where} [torsion_test]"
        _keys(t, ("loaded", "front_support", "rear_supports", "load"), ("loaded", "front_support", "rear_supports"), w)
        rear = t["rear_supports"]
        if not (isinstance(rear, list) and len(rear) == 2):
            raise ParameterError(f"{w}.rear_supports must list two node names, got {rear!r}")
        chosen = [t["loaded"], t["front_support"], *rear]
        for n in chosen:
            if n not in index:
                raise ParameterError(f"{w}: node {n!r} is not defined in [nodes]")
        if len(set(chosen)) != 4:
            raise ParameterError(f"{w}: loaded, front_support and rear_supports must be four different nodes")
        load = t.get("load", 1000.0)
        if isinstance(load, bool) or not isinstance(load, (int, float)) or load == 0.0 or not math.isfinite(load):
            raise ParameterError(f"{w}.load must be a non-zero number in N, got {load!r}")
        torsion = TorsionTest(t["loaded"], t["front_support"], (rear[0], rear[1]), float(load))

    return Frame(
        node_names=names,
        node_xyz=xyz,
        member_nodes=tuple(m_nodes),
        member_section=tuple(m_sec),
        member_material=tuple(m_mat),
        member_divisions=tuple(m_div),
        member_orientation=np.asarray(m_orient),
        section_names=section_names,
        sections=sections,
        material_names=material_names,
        materials=materials,
        mass_nodes=tuple(mass_nodes),
        point_masses=np.asarray(masses, dtype=float).reshape(len(masses)),
        interface=tuple(interface),
        torsion_test=torsion,
        timoshenko=timoshenko,
        lumped_mass=lumped,
    )


def load_frame(path: str | Path | None = None) -> Frame:
    """Load a frame TOML file (default: the shipped FSAE 2009 frame)."""
    table, where = read_toml(path, "jaxveh.fe", "data/fsae_2009_frame.toml", "frame")
    return frame_from_dict(table, where)
