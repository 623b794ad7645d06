"""Test configuration: float64, strict dtype promotion, rank promotion raises.

Every compiled XLA executable holds a few memory mappings of JIT code. A long-lived test
worker that compiles thousands of functions reaches the kernel's `vm.max_map_count`
(65530 by default), and the next compile then segfaults inside XLA's CPU compiler. Each
test module therefore drops JAX's compilation caches when it ends, which frees the
executables it compiled (module-scoped fixtures such as a compiled car are torn down
before this one).
"""

import gc

import jax
import pytest

import jaxveh  # noqa: F401  (enables float64)

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_dtype_promotion", "strict")
jax.config.update("jax_numpy_rank_promotion", "raise")


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_code():
    """Free the module's compiled executables (and their memory mappings) when it ends."""
    yield
    jax.clear_caches()
    gc.collect()
