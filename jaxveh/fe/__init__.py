"""Chassis finite-element model and modal reduction (thesis sections 5.4.2, 6.2.2).

Beam space frames (:class:`Frame`, TOML input), dense assembly, static torsion test,
free-free modal truncation, Craig-Bampton reduction, MAC/NRFD, and the floating-frame
modal invariants packaged as a :class:`ModalBody` for the flexible multibody library.
Everything numeric is differentiable with respect to section sizes, materials and node
coordinates.
"""

from ._analysis import (
    METHODS as METHODS,
    chassis_modes as chassis_modes,
    compare_reductions as compare_reductions,
    export_npz as export_npz,
    mode_labels as mode_labels,
)
from ._assembly import (
    Mesh as Mesh,
    assemble as assemble,
    element_centres as element_centres,
    element_matrices as element_matrices,
    element_strain_energy as element_strain_energy,
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
    frame_modal_body_like as frame_modal_body_like,
    nodal_mass_data as nodal_mass_data,
    split_modes as split_modes,
    straight_beam_body as straight_beam_body,
    straight_tube_frame as straight_tube_frame,
)
from ._craig_bampton import CraigBampton as CraigBampton, craig_bampton as craig_bampton
from ._frame import (
    Frame as Frame,
    TorsionTest as TorsionTest,
    frame_from_dict as frame_from_dict,
    load_frame as load_frame,
)
from ._import import (
    ExternalModel as ExternalModel,
    external_modal_body as external_modal_body,
    external_model_from_arrays as external_model_from_arrays,
    load_external_model as load_external_model,
)
from ._invariants import (
    DEFAULT_DAMPING_RATIO as DEFAULT_DAMPING_RATIO,
    ModalBody as ModalBody,
    ModalInvariants as ModalInvariants,
    damping_parameters as damping_parameters,
    modal_body as modal_body,
    modal_damping_ratios as modal_damping_ratios,
    modal_invariants as modal_invariants,
    skew as skew,
)
from ._mac import mac as mac, nrfd as nrfd
from ._modal import (
    DEGENERACY_RTOL as DEGENERACY_RTOL,
    free_free_modes as free_free_modes,
    generalised_eigh as generalised_eigh,
    rigid_body_modes as rigid_body_modes,
    safe_eigh as safe_eigh,
)
from ._static import (
    TorsionResult as TorsionResult,
    solve_static as solve_static,
    torsion_test as torsion_test,
)
