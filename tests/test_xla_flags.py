"""The XLA CPU flags jaxveh sets on import (jaxveh._xla): by default, only on the measured
jaxlib versions, never twice, never against the user's own setting, never with
JAXVEH_XLA_FLAGS=0. XLA aborts on an unknown flag, so a wrong gate would kill the process."""

import os
import subprocess
import sys

import pytest

from jaxveh import _xla


def test_flags_added_on_tested_versions_only():
    env = {"JAXVEH_XLA_FLAGS": "1"}
    assert _xla.apply_cpu_flags(env, (0, 10, 2)) == _xla.CPU_FLAGS
    assert env["XLA_FLAGS"] == " ".join(_xla.CPU_FLAGS)
    assert _xla.apply_cpu_flags(env, (0, 10, 2)) == ()  # already there: not added twice
    assert env["XLA_FLAGS"] == " ".join(_xla.CPU_FLAGS)
    other = {"JAXVEH_XLA_FLAGS": "1"}
    assert _xla.apply_cpu_flags(other, (0, 11)) == () and "XLA_FLAGS" not in other


def test_user_setting_and_opt_out_are_kept():
    env = {"XLA_FLAGS": "--xla_cpu_use_fusion_emitters=true --xla_force_host_platform_device_count=2",
           "JAXVEH_XLA_FLAGS": "1"}
    assert _xla.apply_cpu_flags(env, (0, 10)) == ()
    assert env["XLA_FLAGS"].startswith("--xla_cpu_use_fusion_emitters=true")
    env = {"XLA_FLAGS": "--xla_force_host_platform_device_count=2", "JAXVEH_XLA_FLAGS": "0"}  # opted out
    assert _xla.apply_cpu_flags(env, (0, 10)) == ()
    assert env["XLA_FLAGS"] == "--xla_force_host_platform_device_count=2"


def test_flags_are_on_by_default_and_a_bad_setting_is_named():
    env = {"XLA_FLAGS": "--xla_force_host_platform_device_count=2"}
    assert _xla.apply_cpu_flags(env, (0, 10, 2)) == _xla.CPU_FLAGS
    assert env["XLA_FLAGS"] == " ".join(("--xla_force_host_platform_device_count=2", *_xla.CPU_FLAGS))
    assert _xla.apply_cpu_flags({"JAXVEH_XLA_FLAGS": ""}, (0, 10, 2)) == _xla.CPU_FLAGS
    with pytest.raises(ValueError, match="JAXVEH_XLA_FLAGS = 'yes' is not allowed"):
        _xla.apply_cpu_flags({"JAXVEH_XLA_FLAGS": "yes"}, (0, 10, 2))


def test_import_sets_flags_that_this_jaxlib_accepts():
    """A fresh interpreter imports jaxveh and runs a computation: the backend starts with the
    flags (an unknown flag would abort it), by default."""
    code = ("import os, jaxveh, jax.numpy as jnp; print(float(jnp.arange(3.0).sum())); "
            "print(os.environ.get('XLA_FLAGS', ''))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                         env={k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "JAXVEH_XLA_FLAGS")})
    assert out.returncode == 0, out.stderr
    total, flags = out.stdout.splitlines()[:2]
    assert total == "3.0"
    expected = _xla.CPU_FLAGS if _xla._jaxlib_version()[:2] in _xla.TESTED_JAXLIB else ()
    assert all(flag in flags for flag in expected)
