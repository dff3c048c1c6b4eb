"""The cycle's references: a guidance's rate and acceleration brought into body axes."""

from __future__ import annotations

import numpy as np

from flight_sw import quaternion as qt
from flight_sw.guidance.mrp_polynomial import MrpPolynomialGuidance
from flight_sw.reference import References, Timeline

NS_PER_S = 1_000_000_000
SAMPLE_TIMES_S = (0.0, 12.5, 47.0, 99.0)
BODY_RTOL = 1e-14  # float products vs numpy's matrix products: round-off only


def test_guidance_rate_and_acceleration_are_in_body_axes() -> None:
    """ω_B = C_BN C_RNᵀ ω_R and the same for dω, against numpy's matrices (a transposed
    C_RN, or C_BN alone, fails: the attitudes differ by tens of degrees)."""
    guidance = MrpPolynomialGuidance()
    refs = References(Timeline(np.array([1.0, 0.0, 0.0, 0.0]), 0), guidance)
    q_BN = qt.normalise(np.array([0.7, -0.3, 0.5, 0.4]))
    for t_s in SAMPLE_TIMES_S:
        t_ns = round(t_s * NS_PER_S)
        ref = guidance.reference(t_ns)
        q_RN, omega_B, domega_B = refs.attitude(t_ns, q_BN)
        c_BR = qt.to_dcm(q_BN) @ qt.to_dcm(ref.q_RN).T
        assert np.array_equal(q_RN, ref.q_RN)
        np.testing.assert_allclose(omega_B, c_BR @ ref.omega_RN_R, rtol=BODY_RTOL,
                                   atol=BODY_RTOL * float(np.abs(ref.omega_RN_R).max()))
        assert domega_B is not None
        np.testing.assert_allclose(domega_B, c_BR @ ref.domega_RN_R, rtol=BODY_RTOL,
                                   atol=BODY_RTOL * float(np.abs(ref.domega_RN_R).max()))
