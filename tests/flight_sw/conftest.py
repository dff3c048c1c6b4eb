"""Shared fixtures of the flight-software algorithm tests: the seed-003 and seed-000 vehicles."""

from __future__ import annotations

import numpy as np
import pytest

from bench.station.valves.layouts import seed000_conventional_16

# Seed 003, Table 1.
SEED003_INERTIA_KGM2 = (15.95, 72.19, 72.19)
SEED003_THRUST_N = 15.0
SEED003_ARM_R_M = 0.45
SEED003_LENGTH_L_M = 0.22


def seed003_layout() -> tuple[np.ndarray, np.ndarray]:
    """Positions (n×3, m) and unit directions (n×3) of the 8 tangential thrusters, body axes."""
    r, l_ = SEED003_ARM_R_M, SEED003_LENGTH_L_M
    positions = np.array(
        [
            (r, 0.0, l_),
            (r, 0.0, -l_),
            (r, l_, 0.0),
            (r, -l_, 0.0),
            (-r, 0.0, l_),
            (-r, 0.0, -l_),
            (-r, l_, 0.0),
            (-r, -l_, 0.0),
        ]
    )
    directions = np.array(
        [
            (0.0, 1.0, 0.0),
            (0.0, -1.0, 0.0),
            (0.0, 0.0, 1.0),
            (0.0, 0.0, -1.0),
            (0.0, -1.0, 0.0),
            (0.0, 1.0, 0.0),
            (0.0, 0.0, -1.0),
            (0.0, 0.0, 1.0),
        ]
    )
    return positions, directions


@pytest.fixture
def layout() -> tuple[np.ndarray, np.ndarray]:
    """The seed-003 thruster layout (positions, directions)."""
    return seed003_layout()


@pytest.fixture
def inertia_kgm2() -> tuple[float, float, float]:
    """The seed-003 principal moments of inertia (Table 1) [kg m²]."""
    return SEED003_INERTIA_KGM2


@pytest.fixture
def max_thrust_n() -> float:
    """The seed-003 thrust level (Table 1) [N]."""
    return SEED003_THRUST_N


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator, so every test run draws the same numbers."""
    return np.random.default_rng(20240531)


# Seed 000: 16 thrusters, 5 N; the reconstructed four-quad layout (bench/station/valves/layouts.py)
# with the fdir_16thr scenario's dimensions; nominal mass and inertia.
SEED000_THRUST_N = 5.0
SEED000_ARM_R_M = 0.5
SEED000_LENGTH_L_M = 0.1
SEED000_NOMINAL_MASS_KG = 100.0
SEED000_NOMINAL_INERTIA_KGM2 = (18.0, 18.0, 24.0)
SEED000_ACTUAL_MASS_KG = 95.0
SEED000_ACTUAL_INERTIA_KGM2 = (17.0, 17.0, 22.0)


def seed000_layout() -> tuple[np.ndarray, np.ndarray]:
    """Positions (16×3, m) and unit directions (16×3) of the seed-000 16-thruster layout."""
    geo = seed000_conventional_16(SEED000_ARM_R_M, SEED000_LENGTH_L_M)
    return np.array([g[0] for g in geo]), np.array([g[1] for g in geo])


@pytest.fixture
def layout16() -> tuple[np.ndarray, np.ndarray]:
    """The seed-000 16-thruster layout (positions, directions)."""
    return seed000_layout()
