"""Statistical and known-answer tests of the gyro, accelerometer and star-tracker models."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bench.station.dynamics.rigid_body import Quat, quat_conjugate, quat_multiply, quat_normalize
from bench.station.sensors.accelerometer import Accelerometer, AccelerometerParams
from bench.station.sensors.gyro import Gyro, GyroParams
from bench.station.sensors.star_tracker import RAD_PER_ARCSEC, StarTracker, StarTrackerParams
from dbc.errors import ConfigError
from tests.values import same_value

SEED = 20240607
N_SAMPLES = 20_000
PERIOD_NS = 5_000_000
PERIOD_S = PERIOD_NS * 1e-9
# Statistical tolerances: a mean of N normals is within 5σ/√N; a sample standard
# deviation within 5·σ/√(2N) (false-failure odds ~1e-6, and the seed is fixed anyway).
N_SIGMA = 5.0
MEAN_TOL_FRACTION = N_SIGMA / math.sqrt(N_SAMPLES)
STD_REL_TOL = N_SIGMA / math.sqrt(2.0 * N_SAMPLES)
ROUNDOFF_TOL = 1e-12
LSB_MULTIPLE_TOL = 1e-9

OMEGA_TRUE = (0.01, -0.02, 0.03)
GYRO_BIAS = (1e-4, -2e-4, 3e-4)
ARW = 1e-4  # rad/√s
F_TRUE = (0.1, -0.2, 0.05)
ACCEL_BIAS = (1e-3, -2e-3, 5e-4)
VRW = 2e-3  # m/s/√s


def _gyro(seed: int = SEED, **kw: object) -> Gyro:
    base: dict[str, object] = {"bias_rad_s": GYRO_BIAS, "arw_rad_sqrt_s": ARW, "period_s": PERIOD_S}
    base.update(kw)
    return Gyro(GyroParams(**base), np.random.default_rng(seed))  # type: ignore[arg-type]


def _gyro_samples(g: Gyro, omega: tuple[float, float, float] = OMEGA_TRUE) -> np.ndarray:
    return np.array([g.sample(k * PERIOD_NS, omega) for k in range(N_SAMPLES)])


# --- gyro ----------------------------------------------------------------------------------------
def test_gyro_bias_and_arw_statistics() -> None:
    """Mean error = bias and σ = ARW/√dt within statistical tolerance (fixed seed)."""
    err = _gyro_samples(_gyro()) - np.array(OMEGA_TRUE)
    sigma = ARW / math.sqrt(PERIOD_S)
    assert np.all(np.abs(err.mean(axis=0) - np.array(GYRO_BIAS)) <= MEAN_TOL_FRACTION * sigma)
    assert np.all(np.abs(err.std(axis=0, ddof=1) / sigma - 1.0) <= STD_REL_TOL)


def test_gyro_noise_scales_with_actual_sample_interval() -> None:
    """σ = ARW/√dt uses the time since the previous sample (here 4× the nominal period)."""
    g = _gyro()
    dt_ns = 4 * PERIOD_NS
    err = np.array([g.sample(k * dt_ns, OMEGA_TRUE) for k in range(N_SAMPLES)])[1:] - OMEGA_TRUE
    sigma = ARW / math.sqrt(dt_ns * 1e-9)
    assert np.all(np.abs(err.std(axis=0, ddof=1) / sigma - 1.0) <= STD_REL_TOL)


def test_gyro_first_sample_known_answer() -> None:
    """First sample = ω + b0 + ARW/√period·n, second adds the walk K√dt·n (same draws)."""
    k_rw = 1e-5
    g = _gyro(bias_rw_rad_s_sqrt_s=k_rw)
    n = np.random.default_rng(SEED).standard_normal((2, 6))
    first = g.sample(1_000, OMEGA_TRUE)
    sn = ARW / math.sqrt(PERIOD_S)
    assert first == pytest.approx(
        tuple(OMEGA_TRUE[i] + GYRO_BIAS[i] + sn * n[0, 3 + i] for i in range(3)), abs=ROUNDOFF_TOL
    )
    dt = 2e-3
    second = g.sample(1_000 + round(dt * 1e9), OMEGA_TRUE)
    bias2 = [GYRO_BIAS[i] + k_rw * math.sqrt(dt) * n[1, i] for i in range(3)]
    assert g.bias_rad_s == pytest.approx(tuple(bias2), abs=ROUNDOFF_TOL)
    sn2 = ARW / math.sqrt(dt)
    assert second == pytest.approx(
        tuple(OMEGA_TRUE[i] + bias2[i] + sn2 * n[1, 3 + i] for i in range(3)), abs=ROUNDOFF_TOL
    )


def test_gyro_bias_random_walk_statistics() -> None:
    """With ARW = 0 the output increments have σ = K·√dt."""
    k_rw = 3e-5
    err = _gyro_samples(_gyro(arw_rad_sqrt_s=0.0, bias_rw_rad_s_sqrt_s=k_rw))
    steps = np.diff(err, axis=0)
    sigma = k_rw * math.sqrt(PERIOD_S)
    assert np.all(np.abs(steps.std(axis=0, ddof=1) / sigma - 1.0) <= STD_REL_TOL)
    assert np.all(np.abs(steps.mean(axis=0)) <= MEAN_TOL_FRACTION * sigma)


def test_gyro_quantises_to_lsb() -> None:
    """Every output is a whole number of LSBs."""
    lsb = 1e-4
    out = _gyro_samples(_gyro(lsb_rad_s=lsb))
    counts = out / lsb
    assert np.all(np.abs(counts - np.round(counts)) <= LSB_MULTIPLE_TOL)
    assert len(np.unique(out[:, 0])) > 1


def test_gyro_saturates() -> None:
    """Rates beyond the range clip to the largest whole-LSB value within the range."""
    lsb, rng_ = 0.003, 0.1
    g = _gyro(lsb_rad_s=lsb, range_rad_s=rng_)
    hi = g.sample(0, (5.0, -5.0, 0.0))
    limit = math.floor(rng_ / lsb) * lsb
    assert hi[0] == pytest.approx(limit, abs=ROUNDOFF_TOL)
    assert hi[1] == pytest.approx(-limit, abs=ROUNDOFF_TOL)
    assert abs(hi[0]) <= rng_
    g2 = _gyro(range_rad_s=rng_)  # no quantisation: clip at the range itself
    assert g2.sample(0, (5.0, 0.0, 0.0))[0] == rng_


def test_gyro_rejects_non_increasing_time() -> None:
    """Samples must be taken in strictly increasing time."""
    g = _gyro()
    g.sample(10, OMEGA_TRUE)
    with pytest.raises(ValueError):
        g.sample(10, OMEGA_TRUE)


def test_same_seed_same_samples() -> None:
    """Same seed → identical sample sequences; another seed → different ones."""
    a = _gyro_samples(_gyro(SEED, bias_rw_rad_s_sqrt_s=1e-5, lsb_rad_s=1e-6))[:200]
    b = _gyro_samples(_gyro(SEED, bias_rw_rad_s_sqrt_s=1e-5, lsb_rad_s=1e-6))[:200]
    c = _gyro_samples(_gyro(SEED + 1, bias_rw_rad_s_sqrt_s=1e-5, lsb_rad_s=1e-6))[:200]
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    st = [StarTracker(StarTrackerParams(10.0, 50.0), np.random.default_rng(SEED)) for _ in range(2)]
    q = quat_normalize((0.5, 0.5, -0.5, 0.2))
    assert [st[0].sample(k, q) for k in range(50)] == [st[1].sample(k, q) for k in range(50)]


# --- accelerometer ------------------------------------------------------------------------------
def test_accelerometer_bias_and_vrw_statistics() -> None:
    """Mean error = bias and σ = VRW/√dt within statistical tolerance."""
    acc = Accelerometer(
        AccelerometerParams(bias_m_s2=ACCEL_BIAS, vrw_m_s_sqrt_s=VRW, period_s=PERIOD_S),
        np.random.default_rng(SEED),
    )
    err = np.array([acc.sample(k * PERIOD_NS, F_TRUE) for k in range(N_SAMPLES)]) - F_TRUE
    sigma = VRW / math.sqrt(PERIOD_S)
    assert np.all(np.abs(err.mean(axis=0) - np.array(ACCEL_BIAS)) <= MEAN_TOL_FRACTION * sigma)
    assert np.all(np.abs(err.std(axis=0, ddof=1) / sigma - 1.0) <= STD_REL_TOL)
    assert acc.bias_m_s2 == ACCEL_BIAS


def test_accelerometer_quantises_and_saturates() -> None:
    """Outputs are whole LSBs and clip at the range."""
    lsb, rng_ = 1e-3, 0.5
    acc = Accelerometer(
        AccelerometerParams(vrw_m_s_sqrt_s=VRW, lsb_m_s2=lsb, range_m_s2=rng_),
        np.random.default_rng(SEED),
    )
    out = np.array([acc.sample(k * PERIOD_NS, F_TRUE) for k in range(1000)])
    assert np.all(np.abs(out / lsb - np.round(out / lsb)) <= LSB_MULTIPLE_TOL)
    sat = acc.sample(10**10, (100.0, -100.0, 0.0))
    assert sat[:2] == pytest.approx((rng_, -rng_), abs=ROUNDOFF_TOL)


# --- star tracker -------------------------------------------------------------------------------
def _error_vectors(st: StarTracker, q_true: Quat) -> np.ndarray:
    """Body-axes rotation vectors θ with q_meas = q_true ⊗ exp(θ/2)."""
    out = []
    for k in range(N_SAMPLES):
        q_meas, valid = st.sample(k * 100_000_000, q_true)
        assert valid
        assert q_meas[0] >= 0.0
        assert abs(math.sqrt(sum(x * x for x in q_meas)) - 1.0) <= ROUNDOFF_TOL
        d = quat_multiply(quat_conjugate(q_true), q_meas)
        if d[0] < 0.0:
            d = (-d[0], -d[1], -d[2], -d[3])
        vn = math.sqrt(d[1] ** 2 + d[2] ** 2 + d[3] ** 2)
        angle = 2.0 * math.atan2(vn, d[0])
        out.append([angle / vn * c for c in d[1:]] if vn > 0.0 else [0.0, 0.0, 0.0])
    return np.array(out)


@pytest.mark.parametrize(
    "boresight", [(0.0, 0.0, 1.0), (1 / math.sqrt(3), -1 / math.sqrt(3), 1 / math.sqrt(3))]
)
def test_star_tracker_error_statistics(boresight: tuple[float, float, float]) -> None:
    """Error angles about / across the boresight have the configured 1σ (arcsec)."""
    cross, about = 8.0, 45.0
    st = StarTracker(StarTrackerParams(cross, about, boresight), np.random.default_rng(SEED))
    q_true = quat_normalize((0.3, -0.6, 0.2, 0.7))
    theta = _error_vectors(st, q_true) / RAD_PER_ARCSEC
    b = np.array(boresight)
    along = theta @ b
    across = np.linalg.norm(theta - np.outer(along, b), axis=1)
    assert abs(along.std(ddof=1) / about - 1.0) <= STD_REL_TOL
    # the cross-boresight error is 2-D: E|θ⊥|² = 2σ⊥²
    rms_across = math.sqrt(float(np.mean(across**2)) / 2.0)
    assert abs(rms_across / cross - 1.0) <= STD_REL_TOL
    assert np.all(np.abs(theta.mean(axis=0)) <= MEAN_TOL_FRACTION * about)


def test_star_tracker_outage_freezes_and_flags_invalid() -> None:
    """During an outage samples are invalid and frozen at the last valid output."""
    st = StarTracker(StarTrackerParams(5.0, 20.0), np.random.default_rng(SEED))
    q = quat_normalize((0.9, 0.1, 0.2, -0.3))
    last, valid = st.sample(0, q)
    assert valid
    st.set_outage(True)
    assert st.sample(1, q) == (last, False)
    assert st.sample(2, quat_normalize((0.1, 0.9, 0.0, 0.0))) == (last, False)
    st.set_outage(False)
    q2, valid2 = st.sample(3, q)
    assert valid2
    assert q2 != last


def test_star_tracker_noiseless_returns_truth_with_positive_scalar() -> None:
    """With zero noise the output is the true quaternion, sign-fixed to q0 ≥ 0."""
    st = StarTracker(StarTrackerParams(), np.random.default_rng(SEED))
    q = quat_normalize((-0.4, 0.5, 0.6, -0.2))
    q_meas, valid = st.sample(0, q)
    assert valid
    assert q_meas == pytest.approx(tuple(-x for x in q), abs=ROUNDOFF_TOL)


# --- configuration -----------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("cls", "key", "value"),
    [
        (GyroParams, "arw_rad_sqrt_s", -1.0),
        (GyroParams, "period_s", 0.0),
        (GyroParams, "range_rad_s", -2.0),
        (GyroParams, "bias_rad_s", (1.0, 2.0)),
        (AccelerometerParams, "vrw_m_s_sqrt_s", math.nan),
        (AccelerometerParams, "lsb_m_s2", -1e-3),
        (StarTrackerParams, "noise_about_arcsec", -5.0),
        (StarTrackerParams, "boresight_B", (0.0, 0.0, 2.0)),
    ],
)
def test_sensor_config_errors_name_key_and_value(cls: type, key: str, value: object) -> None:
    """Invalid sensor parameters raise ConfigError naming the source, key and value."""
    with pytest.raises(ConfigError) as exc:
        cls(**{key: value}, source="scenario.toml [sensors]")
    assert exc.value.key == key
    assert same_value(exc.value.value, value)
    assert key in str(exc.value)
    assert repr(value) in str(exc.value)
    assert str(exc.value).startswith("scenario.toml [sensors]")


def test_range_must_cover_one_lsb() -> None:
    """A saturation range smaller than the LSB is rejected."""
    with pytest.raises(ConfigError) as exc:
        GyroParams(lsb_rad_s=0.1, range_rad_s=0.05)
    assert exc.value.key == "range_rad_s"
