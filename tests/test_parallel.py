"""jaxveh.map_on_cores: a vmapped function over parts of a batch from one thread per core
gives what one call on the whole batch gives (any batch size against any part count,
pytrees in and out), compiles once per part size, and refuses bad batches by name."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh
from jaxveh import ParameterError, map_on_cores


def _field(batch):
    x, scale = batch["x"], batch["scale"]
    return {"sum": jnp.sum(jnp.sin(x) * scale[:, None], axis=1), "x": x * 2.0}


@pytest.mark.parametrize("n, cores", [(1, 2), (2, 2), (5, 2), (7, 3), (8, 4), (3, 8)])
def test_parts_equal_one_call(n, cores):
    rng = np.random.default_rng(n)
    batch = {"x": rng.normal(size=(n, 3)), "scale": rng.normal(size=n)}
    whole = jax.jit(_field)(batch)
    parts = map_on_cores(jax.jit(_field), batch, cores=cores)
    assert parts["sum"].shape == (n,) and parts["x"].shape == (n, 3)
    np.testing.assert_array_equal(parts["sum"], np.asarray(whole["sum"]))
    np.testing.assert_array_equal(parts["x"], np.asarray(whole["x"]))


@pytest.mark.parametrize("n, cores, part_size, calls", [(10, 2, 3, 4), (10, 2, 5, 2), (10, 2, 20, 2), (9, 3, 2, 5),
                                                        (4, 1, 1, 4)])
def test_parts_of_a_given_size_equal_one_call(n, cores, part_size, calls):
    """With ``part_size`` the batch is cut into ``ceil(n / part_size)`` parts (at least one per
    core), each of one size (compiled once), and the cores take them in turn."""
    rng = np.random.default_rng(n)
    batch = {"x": rng.normal(size=(n, 3)), "scale": rng.normal(size=n)}
    whole = jax.jit(_field)(batch)
    sizes = []

    def counted(b):
        sizes.append(b["x"].shape[0])
        return _field(b)

    fn = jax.jit(counted)
    called = []
    parts = map_on_cores(lambda b: called.append(1) or fn(b), batch, cores=cores, part_size=part_size)
    assert len(called) == calls and len(sizes) == 1 and sizes[0] == -(-n // calls)
    np.testing.assert_array_equal(parts["sum"], np.asarray(whole["sum"]))
    np.testing.assert_array_equal(parts["x"], np.asarray(whole["x"]))


def test_compiles_once_per_part_size():
    traces = []

    def traced(batch):
        traces.append(batch.shape)
        return batch + 1.0

    fn = jax.jit(traced)
    for _ in range(3):
        out = map_on_cores(fn, np.arange(6.0), cores=2)
        np.testing.assert_array_equal(out, np.arange(6.0) + 1.0)
    assert traces == [(3,)]


def test_bad_batches_are_refused():
    fn = jax.jit(lambda b: b)
    with pytest.raises(ParameterError, match="same leading axis"):
        map_on_cores(fn, {"a": np.zeros(3), "b": np.zeros(4)})
    with pytest.raises(ParameterError, match="same leading axis"):
        map_on_cores(fn, {"a": np.zeros(3), "b": 1.0})
    with pytest.raises(ParameterError, match="cores must be an int >= 1"):
        map_on_cores(fn, np.zeros(3), cores=0)
    with pytest.raises(ParameterError, match="part_size must be None or an int >= 1"):
        map_on_cores(fn, np.zeros(3), part_size=0)
    with pytest.raises(ParameterError, match="empty"):
        map_on_cores(fn, np.zeros((0, 2)))
    assert jaxveh.core_count() >= 1
