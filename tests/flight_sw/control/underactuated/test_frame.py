"""Seed 004's control frames: axis III along another principal axis, for a triple that
qualifies only there (the canted seed-000 layout)."""

from __future__ import annotations

import numpy as np
import pytest

from bench.station.valves.layouts import LAYOUTS
from dbc.errors import ConfigError
from flight_sw.allocation.effectiveness import effectiveness_matrix
from flight_sw.control.underactuated.frame import FRAME_QUATERNIONS, ControlFrame
from flight_sw.control.underactuated.geometry import CONTROL_FRAMES, qualifying_triples
from flight_sw.control.underactuated.invariants import target_z_in_B
from flight_sw.quaternion import from_rotation_vector, to_dcm

TOL = 1e-12
SEED000_NOMINAL_INERTIA = np.diag([18.0, 18.0, 24.0])  # fdir_16thr's [vehicle.nominal]
SEED000_MASS_KG = 100.0
N_RANDOM = 20


def canted_effectiveness() -> np.ndarray:
    """The 6×16 effectiveness matrix of the canted seed-000 layout (scenario dimensions)."""
    geo = LAYOUTS["seed000_canted_16"](0.5, 0.1)
    return effectiveness_matrix(np.array([g[0] for g in geo]), np.array([g[1] for g in geo]))


@pytest.mark.parametrize("name", [n for n, _ in CONTROL_FRAMES])
def test_tabled_quaternion_is_the_frame_matrix(name: str) -> None:
    """C(q_KB) of each tabled quaternion is the control frame's matrix, a unit quaternion."""
    frame = ControlFrame(name)
    assert np.linalg.norm(FRAME_QUATERNIONS[name]) == pytest.approx(1.0, abs=TOL)
    np.testing.assert_allclose(to_dcm(frame.q_KB), dict(CONTROL_FRAMES)[name], atol=TOL)


@pytest.mark.parametrize("name", [n for n, _ in CONTROL_FRAMES])
def test_attitude_rate_and_torque_map_consistently(name: str) -> None:
    """C(q_KR) = C_KB C(q_BR) for random attitudes; ω and T go to K and back unchanged."""
    frame = ControlFrame(name)
    rng = np.random.default_rng(5)
    for _ in range(N_RANDOM):
        q_BR = from_rotation_vector(rng.normal(size=3))
        np.testing.assert_allclose(to_dcm(frame.q_KR(q_BR)), frame.c_KB @ to_dcm(q_BR),
                                   atol=TOL)
        v = rng.normal(size=3)
        np.testing.assert_allclose(frame.torque_B(frame.omega_K(v)), v, atol=TOL)


def test_axis_III_of_the_x_frame_is_body_x() -> None:
    """In frame III=+x, a body whose x axis lies along z_R has axis III along z_R, and a
    torque about axis III is a torque about body x."""
    frame = ControlFrame("III=+x")
    q_BR = from_rotation_vector(np.array([0.0, -np.pi / 2.0, 0.0]))  # x_B along z_R
    np.testing.assert_allclose(target_z_in_B(q_BR), [1.0, 0.0, 0.0], atol=TOL)
    np.testing.assert_allclose(target_z_in_B(frame.q_KR(q_BR)), [0.0, 0.0, 1.0], atol=TOL)
    np.testing.assert_allclose(frame.torque_B(np.array([0.0, 0.0, 2.0])), [2.0, 0.0, 0.0],
                               atol=TOL)


def test_canted_triples_model_in_their_frame_with_the_same_thrusts() -> None:
    """Every triple the check qualifies in some frame builds a model in that frame, and
    the thrusts it gives a K torque are those the body columns need for the same torque
    in body axes (the valves are commanded as they are)."""
    b = canted_effectiveness()
    good, _ = qualifying_triples(b, SEED000_NOMINAL_INERTIA, frames=CONTROL_FRAMES)
    assert len(good) == 20
    rng = np.random.default_rng(6)
    for fc in good:
        frame = ControlFrame(fc.frame)
        model = frame.three_thrusters(b, SEED000_NOMINAL_INERTIA, SEED000_MASS_KG,
                                      fc.check.thrusters)
        t_K = model.torque_B_Nm(*rng.normal(scale=0.2, size=2))  # a torque the three make
        f = model.thrust_N(t_K)
        assert np.all(f >= -TOL)
        np.testing.assert_allclose(b[3:, list(fc.check.thrusters)] @ f, frame.torque_B(t_K),
                                   atol=TOL)


def test_a_triple_outside_its_frame_or_layout_is_refused() -> None:
    """A qualifying triple in the wrong frame, bad indices or an unknown frame: ConfigError
    naming what is wrong."""
    b = canted_effectiveness()
    good, _ = qualifying_triples(b, SEED000_NOMINAL_INERTIA, frames=CONTROL_FRAMES)
    along_x = next(g.check.thrusters for g in good if g.frame == "III=+x")
    with pytest.raises(ConfigError, match="J_I = J_II"):
        ControlFrame("III=+z").three_thrusters(b, SEED000_NOMINAL_INERTIA, SEED000_MASS_KG,
                                               along_x)
    with pytest.raises(ConfigError, match=r"\(0, 1, 16\)"):
        ControlFrame("III=+x").three_thrusters(b, SEED000_NOMINAL_INERTIA, SEED000_MASS_KG,
                                               (0, 1, 16))
    with pytest.raises(ConfigError, match="III=x"):
        ControlFrame("III=x")
