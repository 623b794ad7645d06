"""Test configuration: float64, strict dtype promotion, rank promotion raises."""

import jax

import jaxveh  # noqa: F401  (enables float64)

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_dtype_promotion", "strict")
jax.config.update("jax_numpy_rank_promotion", "raise")
