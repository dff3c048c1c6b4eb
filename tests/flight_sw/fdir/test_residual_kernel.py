"""The residual FDIR's float kernel against its numpy reference form.

Back to back on random windows of the 16-thruster sizes (50 accelerometer samples, some
thrusters stuck open or known failed, windows without a linear channel): the window
residual, the per-hypothesis gain and β, and each hypothesis's signature.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flight_sw.fdir import residual_kernel as kernel
from tests.flight_sw.fdir.residual_reference import hypotheses, window_residual

SEED = 20261207
CASES = 100
N_THR = 16
SAMPLES = 50
DT_S = 0.01
SPAN_S = 0.5
BETA_MAX = 1.1
BEYOND = 1.5  # thrust-times and fractions up to 1.5× their physical maxima
NOISE = [1e-4, 0.05, 0.05, 1e-3, 5e-3, 1e-3]  # gyro, model, thrust, edge, accel, bias
# Two summation orders of the same sums (index order vs numpy's products and pairwise
# sums), relative to the largest entry of each result.
RTOL = 1e-11


def _close(got: object, want: np.ndarray) -> None:
    got_a = np.asarray(got, dtype=float)
    scale = np.abs(want[np.isfinite(want)]).max(initial=1.0)
    np.testing.assert_allclose(got_a, want, rtol=0.0, atol=RTOL * scale)


@pytest.mark.parametrize(("samples", "beyond"), [(SAMPLES, 1.0), (1, 1.0), (SAMPLES, BEYOND)])
def test_kernel_matches_the_numpy_form(samples: int, beyond: float) -> None:
    """z, the regressors, gain, β and signatures equal the reference (1 sample: no linear
    channel), with stuck-open and known-failed thrusters among random ones; ``beyond`` > 1
    lets thrust-times exceed the window and fractions exceed 1, so the clips of the
    open-hypothesis times (at 0) are exercised."""
    rng = np.random.default_rng(SEED)
    for _ in range(CASES):
        ang = rng.normal(scale=0.1, size=(3, N_THR))
        lin = rng.normal(scale=0.05, size=(3, N_THR))
        j = np.diag(rng.uniform(5.0, 20.0, size=3)) + 0.3 * np.eye(3)[::-1]
        tau_s = rng.uniform(0.0, beyond * SPAN_S, size=N_THR)
        edges = rng.integers(0, 3, size=N_THR).astype(float)
        w_a, w_b = rng.normal(scale=0.05, size=3), rng.normal(scale=0.05, size=3)
        fs = rng.normal(scale=0.02, size=(samples, 3))
        frac = rng.uniform(0.0, beyond, size=(samples, N_THR))
        rate = rng.uniform(0.0, 300.0, size=(samples, N_THR))
        bias = rng.normal(scale=1e-3, size=3)
        stuck = rng.uniform(size=N_THR) < 0.1
        known = stuck | (rng.uniform(size=N_THR) < 0.1)
        tau_cmd = np.where(stuck, 0.0, tau_s)
        ref = window_residual(ang, lin, j, tau_s, edges, w_a, w_b, SPAN_S, fs, frac, rate,
                              bias, DT_S, NOISE)
        per_sample = [kernel.sample_terms(fs[s].tolist(), frac[s].tolist(), rate[s].tolist(),
                                          lin.tolist(), NOISE) for s in range(samples)]
        linear = samples >= 2
        z, h_ang, h_lin, u_s, w_lin, mean = kernel.window_residual(
            ang.tolist(), lin.tolist(), j.tolist(), np.linalg.inv(j).tolist(), tau_s.tolist(),
            edges.tolist(), w_a.tolist(), w_b.tolist(), SPAN_S,
            fs.tolist() if linear else [], [t for t, _ in per_sample] if linear else [],
            frac.tolist() if linear else [], bias.tolist(), DT_S, NOISE)
        for got, key in ((z, "z"), (h_ang, "h_ang"), (h_lin, "h_lin"), (u_s, "u_s")):
            _close(got, ref[key])
        assert (mean is None) == (ref["mean"] is None)
        if mean is not None:
            _close(mean, ref["mean"])
            _close(w_lin, ref["w_lin"])
        ivl = [i for _, i in per_sample] if linear else []
        frac_used = frac if linear else np.zeros((0, N_THR))
        gain, beta = kernel.hypotheses(z, h_ang, tau_cmd.tolist(), SPAN_S, frac_used.tolist(),
                                       stuck.tolist(), w_lin, ivl, lin.tolist(), known.tolist(),
                                       BETA_MAX)
        g_ref, b_ref, sig_ref = hypotheses(np.array(z), np.array(h_ang), np.array(h_lin),
                                           tau_cmd, SPAN_S, np.array(u_s), frac_used, stuck,
                                           ref["w_lin"], ref["inv_var"], lin, known, BETA_MAX,
                                           DT_S)
        assert np.array_equal(np.isinf(gain), np.isinf(g_ref))
        _close(gain, g_ref)
        _close(beta, b_ref)
        for h in range(2 * N_THR):
            sig = kernel.signature(h, h_ang, h_lin, tau_cmd.tolist(), SPAN_S, u_s,
                                   stuck.tolist(), frac_used.shape[0], DT_S)
            _close(sig, sig_ref[:, h])


def test_best_hypothesis_and_margin_follow_numpy_on_ties_and_nan() -> None:
    """The hypothesis choice is np.argmax's (first of equal maxima, first NaN) and the
    other-thruster maximum np.max's (NaN propagates, −inf when all are masked)."""
    from flight_sw.fdir.rate_residual import _argmax, _max_or_nan

    for gains in ([1.0, 3.0, 3.0, -math.inf], [-math.inf] * 3, [2.0, math.nan, 5.0, math.nan],
                  [math.nan, 1.0]):
        assert _argmax(gains) == int(np.argmax(np.array(gains)))
        want = float(np.max(np.array(gains)))
        got = _max_or_nan(gains)
        assert (math.isnan(got) and math.isnan(want)) or got == want
    assert _max_or_nan([]) == -math.inf
