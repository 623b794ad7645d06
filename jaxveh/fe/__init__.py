"""Chassis finite-element model and modal reduction (thesis sections 5.4.2, 6.2.2).

Beam space frames (:class:`Frame`, TOML input), dense assembly, static torsion test,
free-free modal truncation, Craig-Bampton reduction, MAC/NRFD, and the floating-frame
modal invariants packaged as a :class:`ModalBody` for the flexible multibody library.
Everything numeric is differentiable with respect to section sizes, materials and node
coordinates.
"""

from ._analysis import (
    METHODS as METHODS,
)
from ._analysis import (
    chassis_modes as chassis_modes,
)
from ._analysis import (
    compare_reductions as compare_reductions,
)
from ._analysis import (
    export_npz as export_npz,
)
from ._analysis import (
    mode_labels as mode_labels,
)
from ._assembly import (
    Mesh as Mesh,
)
from ._assembly import (
    assemble as assemble,
)
from ._assembly import (
    element_centres as element_centres,
)
from ._assembly import (
    element_matrices as element_matrices,
)
from ._assembly import (
    element_strain_energy as element_strain_energy,
)
from ._assembly import (
    frame_mass as frame_mass,
)
from ._assembly import (
    frame_mesh as frame_mesh,
)
from ._assembly import (
    mesh_xyz as mesh_xyz,
)
from ._assembly import (
    with_sections as with_sections,
)
from ._beam import (
    CircularTube as CircularTube,
)
from ._beam import (
    Material as Material,
)
from ._beam import (
    RectangularTube as RectangularTube,
)
from ._beam import (
    SectionProperties as SectionProperties,
)
from ._body import (
    frame_modal_body as frame_modal_body,
)
from ._body import (
    nodal_mass_data as nodal_mass_data,
)
from ._body import (
    split_modes as split_modes,
)
from ._body import (
    straight_beam_body as straight_beam_body,
)
from ._body import (
    straight_tube_frame as straight_tube_frame,
)
from ._craig_bampton import CraigBampton as CraigBampton
from ._craig_bampton import craig_bampton as craig_bampton
from ._frame import (
    Frame as Frame,
)
from ._frame import (
    TorsionTest as TorsionTest,
)
from ._frame import (
    frame_from_dict as frame_from_dict,
)
from ._frame import (
    load_frame as load_frame,
)
from ._import import (
    ExternalModel as ExternalModel,
)
from ._import import (
    external_modal_body as external_modal_body,
)
from ._import import (
    external_model_from_arrays as external_model_from_arrays,
)
from ._import import (
    load_external_model as load_external_model,
)
from ._invariants import (
    DEFAULT_DAMPING_RATIO as DEFAULT_DAMPING_RATIO,
)
from ._invariants import (
    ModalBody as ModalBody,
)
from ._invariants import (
    ModalInvariants as ModalInvariants,
)
from ._invariants import (
    damping_parameters as damping_parameters,
)
from ._invariants import (
    modal_body as modal_body,
)
from ._invariants import (
    modal_damping_ratios as modal_damping_ratios,
)
from ._invariants import (
    modal_invariants as modal_invariants,
)
from ._invariants import (
    skew as skew,
)
from ._mac import mac as mac
from ._mac import nrfd as nrfd
from ._modal import (
    DEGENERACY_RTOL as DEGENERACY_RTOL,
)
from ._modal import (
    free_free_modes as free_free_modes,
)
from ._modal import (
    generalised_eigh as generalised_eigh,
)
from ._modal import (
    rigid_body_modes as rigid_body_modes,
)
from ._modal import (
    safe_eigh as safe_eigh,
)
from ._static import (
    TorsionResult as TorsionResult,
)
from ._static import (
    solve_static as solve_static,
)
from ._static import (
    torsion_test as torsion_test,
)
