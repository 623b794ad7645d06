"""Import of external M/K matrices (NPZ and Matrix Market) with a node/DOF table."""

import numpy as np
import pytest
import scipy.io
from test_fe_reduction import box_frame

import jaxveh.fe as fe
from jaxveh.params import ParameterError

#: Same matrices, permuted and re-read: only round-off (and text round-trip) differences.
RTOL_ROUNDTRIP = 1e-9


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    frame = box_frame()
    path = tmp_path_factory.mktemp("exp") / "box.npz"
    data = fe.export_npz(frame, path, n_modes=6)
    return frame, path, data


def test_npz_roundtrip_gives_same_modes_and_body(exported):
    frame, path, data = exported
    model = fe.load_external_model(path)
    f, _ = fe.free_free_modes(model.K, model.M, 6)
    np.testing.assert_allclose(f, data["frequencies_hz"], rtol=RTOL_ROUNDTRIP)
    body = fe.external_modal_body(model, 4, ("s0c0", "s2c3"))
    ref = fe.frame_modal_body(frame, 4, points=("s0c0", "s2c3"))
    np.testing.assert_allclose(body.invariants.J0, ref.invariants.J0, rtol=RTOL_ROUNDTRIP)
    np.testing.assert_allclose(body.frequencies_hz, ref.frequencies_hz, rtol=RTOL_ROUNDTRIP)
    np.testing.assert_allclose(body.point_xyz, ref.point_xyz)


def test_permuted_dof_table_and_matrix_market(exported, tmp_path):
    _, _, d = exported
    rng = np.random.default_rng(3)
    perm = rng.permutation(d["K"].shape[0])
    K, M, dof_map = d["K"][np.ix_(perm, perm)], d["M"][np.ix_(perm, perm)], d["dof_map"][perm]
    scipy.io.mmwrite(str(tmp_path / "K.mtx"), scipy.sparse.coo_matrix(K), symmetry="symmetric", precision=17)
    scipy.io.mmwrite(str(tmp_path / "M.mtx"), scipy.sparse.coo_matrix(M), symmetry="symmetric", precision=17)
    np.savetxt(tmp_path / "nodes.csv", np.column_stack([d["node_ids"], d["node_xyz"]]), delimiter=",", fmt="%.17g")
    np.savetxt(tmp_path / "dofs.csv", dof_map, delimiter=",", fmt="%d")
    files = (tmp_path / n for n in ("K.mtx", "M.mtx", "nodes.csv", "dofs.csv"))
    model = fe.load_external_model(*files)
    f, _ = fe.free_free_modes(model.K, model.M, 6)
    np.testing.assert_allclose(f, d["frequencies_hz"], rtol=RTOL_ROUNDTRIP)


def test_import_errors(exported):
    _, _, d = exported
    args = dict(K=d["K"], M=d["M"], node_ids=d["node_ids"], node_xyz=d["node_xyz"], dof_map=d["dof_map"])
    bad_map = d["dof_map"].copy()
    bad_map[1] = bad_map[0]
    with pytest.raises(ParameterError, match="lists node 1 component 1 twice"):
        fe.external_model_from_arrays(**{**args, "dof_map": bad_map})
    with pytest.raises(ParameterError, match="not symmetric"):
        asym = d["K"] + 1e-3 * np.abs(d["K"]).max() * np.triu(np.ones_like(d["K"]), 1)
        fe.external_model_from_arrays(**{**args, "K": asym})
    with pytest.raises(ParameterError, match="every node must carry six DOF"):
        fe.external_model_from_arrays(**{**args, "node_ids": d["node_ids"][:-1], "node_xyz": d["node_xyz"][:-1]})
    with pytest.raises(ParameterError, match="does not exist"):
        fe.load_external_model("/nonexistent/model.npz")
