"""Chassis finite-element model and modal reduction (thesis sections 5.4.2, 6.2.2).

Beam space frames (:class:`Frame`, TOML input), dense assembly, static torsion test,
free-free modal truncation, Craig-Bampton reduction, MAC/NRFD, and the floating-frame
modal invariants packaged as a :class:`ModalBody` for the flexible multibody library.
Everything numeric is differentiable with respect to section sizes, materials and node
coordinates.
"""

from ._assembly import (
    Mesh as Mesh,
    assemble as assemble,
    element_matrices as element_matrices,
    frame_mass as frame_mass,
    frame_mesh as frame_mesh,
    mesh_xyz as mesh_xyz,
    with_sections as with_sections,
)
from ._beam import (
    CircularTube as CircularTube,
    Material as Material,
    RectangularTube as RectangularTube,
    SectionProperties as SectionProperties,
)
from ._body import (
    frame_modal_body as frame_modal_body,
    nodal_mass_data as nodal_mass_data,
    split_modes as split_modes,
    straight_beam_body as straight_beam_body,
    straight_tube_frame as straight_tube_frame,
)
from ._frame import (
    Frame as Frame,
    TorsionTest as TorsionTest,
    frame_from_dict as frame_from_dict,
    load_frame as load_frame,
)
from ._invariants import (
    ModalBody as ModalBody,
    ModalInvariants as ModalInvariants,
    modal_body as modal_body,
    modal_invariants as modal_invariants,
    skew as skew,
)
from ._modal import (
    DEGENERACY_RTOL as DEGENERACY_RTOL,
    free_free_modes as free_free_modes,
    generalised_eigh as generalised_eigh,
    rigid_body_modes as rigid_body_modes,
    safe_eigh as safe_eigh,
)
