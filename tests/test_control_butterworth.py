"""Digital Butterworth low-pass filter against ``scipy.signal.butter``."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal
from jax.test_util import check_grads

from jaxveh.control import butterworth_lowpass

FS = 100.0
DT = 1.0 / FS
#: Two float64 realisations of the same transfer function; the filter poles sit near
#: z = 1 (2 Hz at 100 Hz), so the response is conditioned ~1e3 worse than eps.
RESPONSE_ATOL = 1e-11
POLE_ATOL = 1e-11
#: Central finite difference with h = 1e-6 Hz.
FD_RTOL = 1e-6


def _response(f, freqs_hz):
    z = np.exp(2j * np.pi * np.asarray(freqs_hz) * DT)
    a, b, c, d = (np.asarray(x) for x in (f.a, f.b, f.c, f.d))
    n = a.shape[0]
    return np.array([(c @ np.linalg.solve(zi * np.eye(n) - a, b) + d)[0, 0] for zi in z])


@pytest.mark.parametrize("order", [1, 2, 3, 4, 5])
@pytest.mark.parametrize("cutoff_hz", [2.0, 15.0])
def test_frequency_response_matches_scipy(order, cutoff_hz):
    filt = butterworth_lowpass(order, cutoff_hz, DT)
    freqs = np.linspace(0.0, 49.9, 200)
    z, p, k = scipy.signal.butter(order, cutoff_hz, fs=FS, output="zpk")
    _, reference = scipy.signal.freqz_zpk(z, p, k, worN=freqs, fs=FS)
    np.testing.assert_allclose(_response(filt, freqs), reference, atol=RESPONSE_ATOL)
    poles = np.sort_complex(np.linalg.eigvals(np.asarray(filt.a)))
    np.testing.assert_allclose(poles, np.sort_complex(p), atol=POLE_ATOL)


def test_thesis_filter_unit_dc_gain_and_minus_3db_at_cutoff():
    filt = butterworth_lowpass(4, 2.0, DT)
    dc, cut = _response(filt, [0.0, 2.0])
    np.testing.assert_allclose(abs(dc), 1.0, atol=RESPONSE_ATOL)
    np.testing.assert_allclose(abs(cut), 1.0 / np.sqrt(2.0), atol=RESPONSE_ATOL)
    # SciPy's own state-space realisation (butter(..., output="ss") in older SciPy).
    ss_ref = scipy.signal.zpk2ss(*scipy.signal.butter(4, 2.0, fs=FS, output="zpk"))
    omega = 2 * np.pi * np.array([0.5, 1.0, 3.0]) * DT
    _, reference = scipy.signal.dfreqresp(scipy.signal.dlti(*ss_ref, dt=DT), omega)
    np.testing.assert_allclose(_response(filt, [0.5, 1.0, 3.0]), reference, atol=RESPONSE_ATOL)


def test_gradient_wrt_cutoff_matches_finite_differences():
    def impulse_energy(fc):
        """Sum of squares of the first 300 impulse-response samples (grows with fc)."""
        filt = butterworth_lowpass(4, fc, DT)

        def step(x, _):
            return filt.a @ x, (filt.c @ x)[0, 0]

        _, samples = jax.lax.scan(step, filt.b, None, length=300)
        return filt.d[0, 0] ** 2 + jnp.sum(samples**2)

    fc, h = 2.0, 1e-6
    fd = (impulse_energy(fc + h) - impulse_energy(fc - h)) / (2 * h)
    np.testing.assert_allclose(jax.grad(impulse_energy)(jnp.asarray(fc)), fd, rtol=FD_RTOL)


def test_check_grads_wrt_cutoff_and_sample_time():
    def matrices(x):
        f = butterworth_lowpass(4, x[0], x[1])
        return jnp.concatenate([f.a.ravel(), f.b.ravel(), f.c.ravel(), f.d.ravel()])

    check_grads(jax.jit(matrices), (jnp.asarray([2.0, 0.01]),), order=2, modes=("fwd", "rev"), eps=1e-6)


def test_bad_order_and_cutoff_raise():
    with pytest.raises(ValueError, match="order must be a Python int >= 1"):
        butterworth_lowpass(0, 2.0, DT)
    with pytest.raises(Exception, match="Nyquist"):
        butterworth_lowpass(4, 60.0, DT)
