"""Three push-only thrusters as an underactuated actuator, and the configuration check.

What it does: for three thrusters (positions ``r_thr_B_m``, unit directions ``d_thr_B``,
body = principal axes) builds the torque matrix ``M = [r_i × d_i]`` and force matrix
``D = [d_i]`` of seed 004 §2 (eqs. 5–9): thrusts ``f = M⁻¹ T`` for a torque T, the body
force ``F_B = P T`` with ``P = D M⁻¹`` (eq. 9: the force is a function of the torque).
Conditions of §2.1: (i) bidirectional torque about axes I and II: the I–II projections
of the three torque columns positively span the plane; (ii) the axis-III torque is
positive whenever any thruster fires (every column's III component > 0); (iii) the force
along axis III is bidirectional (direction components along III of both signs). Two
more the controller needs: distinct inertias about I and II (else axis III cannot be
turned), and Step D authority: ``ρ = |P_{xy,3}| > 0`` (x–y motion from the de-spin) and
``κ = P_33 J_III / m ≠ 0`` (z motion from the de-spin, eq. 21).

:func:`qualifying_triples` is the configuration check: every set of three working
thrusters of a layout (6×n effectiveness, failure mask) tested against the conditions.

Units: N, N m, m, kg, kg m². Assumptions: a diagonal inertia (body axes are the
principal axes; axis III is body z; a set whose III torques are all negative qualifies
after turning the body frame 180° about x, which this controller does not do: reported).
Source: seed 004 §2.1–2.3 (eqs. 5–9) and conditions (i)–(iii).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from dbc.errors import ConfigError

_SOURCE = "seed-004 thrusters"

SPAN_MARGIN = 1e-9
"""Smallest barycentric weight of the origin in the I–II torque triangle (condition i)."""
SINGULAR_RCOND = 1e-9
"""Reciprocal condition number below which M is singular (torques not independent)."""
INERTIA_DISTINCT_REL = 1e-3
"""Relative difference J_I vs J_II below which axis III is uncontrollable (§2.1 (i))."""


@dataclass(frozen=True)
class TripleCheck:
    """The conditions of seed 004 §2.1 for one set of three thrusters (indices)."""

    thrusters: tuple[int, int, int]
    independent: bool  # M nonsingular
    torque_I_II_bidirectional: bool  # (i)
    torque_III_positive: bool  # (ii), positive sense
    torque_III_negative: bool  # (ii) in the negative sense (needs a flipped body frame)
    force_III_bidirectional: bool  # (iii)
    inertia_I_II_distinct: bool

    @property
    def qualifies(self) -> bool:
        """All conditions hold in the sense this controller runs (positive III torque)."""
        return (self.independent and self.torque_I_II_bidirectional
                and self.torque_III_positive and self.force_III_bidirectional
                and self.inertia_I_II_distinct)

    def why_not(self) -> str:
        """The failed conditions, in words ('' when it qualifies)."""
        out = []
        if not self.independent:
            out.append("torques not independent")
        if not self.torque_I_II_bidirectional:
            out.append("(i) torque about I/II not bidirectional")
        if not self.torque_III_positive:
            out.append("(ii) torque about III not always positive"
                       + (" (always negative: flip the body frame)"
                          if self.torque_III_negative else ""))
        if not self.force_III_bidirectional:
            out.append("(iii) force along III not bidirectional")
        if not self.inertia_I_II_distinct:
            out.append("J_I = J_II")
        return "; ".join(out)


def _in_triangle(p2: np.ndarray) -> bool:
    """Is the origin strictly inside the triangle of the three 2-D points (columns)?"""
    a = np.vstack((p2, np.ones(3)))
    try:
        w = np.linalg.solve(a, np.array([0.0, 0.0, 1.0]))
    except np.linalg.LinAlgError:
        return False
    return bool(np.all(w > SPAN_MARGIN))


def check_triple(torque_B: np.ndarray, force_B: np.ndarray, inertia_diag: np.ndarray,
                 thrusters: tuple[int, int, int]) -> TripleCheck:
    """Conditions (i)–(iii) for torque columns ``torque_B`` (3×3, per unit thrust) and
    force columns ``force_B`` (3×3 unit directions) of the thrusters ``thrusters``."""
    m = np.asarray(torque_B, dtype=float)
    d = np.asarray(force_B, dtype=float)
    s = np.linalg.svd(m, compute_uv=False)
    independent = bool(s[-1] > SINGULAR_RCOND * max(s[0], 1e-300))
    j1, j2 = float(inertia_diag[0]), float(inertia_diag[1])
    return TripleCheck(
        thrusters=thrusters,
        independent=independent,
        torque_I_II_bidirectional=_in_triangle(m[:2]),
        torque_III_positive=bool(np.all(m[2] > 0.0)),
        torque_III_negative=bool(np.all(m[2] < 0.0)),
        force_III_bidirectional=bool(np.any(d[2] > 0.0) and np.any(d[2] < 0.0)),
        inertia_I_II_distinct=abs(j1 - j2) > INERTIA_DISTINCT_REL * max(j1, j2),
    )


CONTROL_FRAMES: tuple[tuple[str, np.ndarray], ...] = (
    ("III=+z", np.eye(3)),
    ("III=-z", np.diag([1.0, -1.0, -1.0])),
    ("III=+x", np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])),
    ("III=-x", np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]])),
    ("III=+y", np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])),
    ("III=-y", np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])),
)
"""The control frames K tried by the check: rows are axes I, II, III in body axes
(right-handed: cyclic permutations of the principal axes, each also turned 180° about I).
The controller itself runs in the first (axis III = +z_B)."""


@dataclass(frozen=True)
class FrameCheck:
    """One triple checked in one control frame."""

    frame: str
    check: TripleCheck


def qualifying_triples(effectiveness: np.ndarray, inertia_B_kgm2: np.ndarray,
                       mask: np.ndarray | None = None,
                       frames: tuple[tuple[str, np.ndarray], ...] = CONTROL_FRAMES[:1],
                       ) -> tuple[list[FrameCheck], list[FrameCheck]]:
    """The configuration check: (qualifying, failing) sets of three working thrusters.

    ``effectiveness``: 6×n, rows force (unit directions) then torque per newton (the
    layout's effectiveness matrix); ``mask``: True = thruster available (default all);
    ``frames``: the control frames to try (default: the controller's, axis III = +z_B;
    :data:`CONTROL_FRAMES` for all six). A triple fails only if it fails in every frame.
    """
    b = np.asarray(effectiveness, dtype=float)
    if b.ndim != 2 or b.shape[0] != 6:
        raise ConfigError(_SOURCE, "effectiveness", b.shape, "a 6×n matrix")
    n = b.shape[1]
    ok = np.ones(n, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    if ok.shape != (n,):
        raise ConfigError(_SOURCE, "mask", ok.shape, f"{n} flags")
    j = principal_diag(inertia_B_kgm2)
    good: list[FrameCheck] = []
    bad: list[FrameCheck] = []
    for idx in itertools.combinations(np.flatnonzero(ok).tolist(), 3):
        cols = list(idx)
        first: FrameCheck | None = None
        for name, k in frames:
            c = check_triple(k @ b[3:, cols], k @ b[:3, cols], np.abs(k) @ j,
                             (idx[0], idx[1], idx[2]))
            if c.qualifies:
                good.append(FrameCheck(name, c))
                break
            first = first or FrameCheck(name, c)
        else:
            assert first is not None
            bad.append(first)
    return good, bad


def principal_diag(inertia_B_kgm2: np.ndarray) -> np.ndarray:
    """The diagonal (J_x, J_y, J_z) of a diagonal inertia [kg m²]; ConfigError otherwise."""
    j = np.asarray(inertia_B_kgm2, dtype=float)
    if j.shape != (3, 3):
        raise ConfigError(_SOURCE, "inertia_B_kgm2", j.shape, "a 3×3 matrix")
    off = j - np.diag(np.diag(j))
    if np.max(np.abs(off)) > 1e-9 * np.max(np.abs(j)):
        raise ConfigError(_SOURCE, "inertia_B_kgm2", j.tolist(),
                          "a diagonal inertia (seed 004: body axes = principal axes)")
    return np.diag(j).copy()


@dataclass(frozen=True)
class ThreeThrusters:
    """The model of three push-only thrusters the seed-004 steps are built on.

    ``torque_B`` 3×3 (columns r_i × d_i, N m per N), ``force_B`` 3×3 (columns d_i),
    ``inertia_diag_kgm2`` (J_I, J_II, J_III), ``mass_kg``. Validated: the set must qualify.
    """

    torque_B: np.ndarray
    force_B: np.ndarray
    inertia_diag_kgm2: np.ndarray
    mass_kg: float
    thrusters: tuple[int, int, int] = (0, 1, 2)
    m_inv: np.ndarray = field(init=False, repr=False)
    p: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.mass_kg > 0.0:
            raise ConfigError(_SOURCE, "mass_kg", self.mass_kg, "> 0")
        c = check_triple(self.torque_B, self.force_B, self.inertia_diag_kgm2, self.thrusters)
        if not c.qualifies:
            raise ConfigError(_SOURCE, "thrusters", self.thrusters,
                              f"a set meeting seed 004's conditions: {c.why_not()}")
        m_inv = np.linalg.inv(np.asarray(self.torque_B, dtype=float))
        object.__setattr__(self, "m_inv", m_inv)
        object.__setattr__(self, "p", np.asarray(self.force_B, dtype=float) @ m_inv)

    @property
    def kappa_m_s_per_rad_s(self) -> float:
        """κ = P_33 J_III / m: z velocity per unit spin rate in single spin (eq. 21) [m]."""
        return float(self.p[2, 2] * self.inertia_diag_kgm2[2] / self.mass_kg)

    @property
    def rho(self) -> float:
        """|P_{xy,3}|: body x–y force per unit axis-III torque [N per N m]."""
        return float(np.hypot(self.p[0, 2], self.p[1, 2]))

    @property
    def alpha_rad(self) -> float:
        """Direction of the x–y force of a pure axis-III torque in body axes [rad]."""
        return float(np.arctan2(self.p[1, 2], self.p[0, 2]))

    @property
    def lateral_m_per_rad_s(self) -> float:
        """λ = ρ J_III / m: x–y velocity scale per unit spin-rate change [m]."""
        return self.rho * float(self.inertia_diag_kgm2[2]) / self.mass_kg

    def thrust_N(self, torque_B_Nm: np.ndarray) -> np.ndarray:
        """f = M⁻¹ T: the three thrusts giving torque T (may be negative if T is not in
        the cone; callers pick T3 with :meth:`min_torque_III_Nm`)."""
        return self.m_inv @ np.asarray(torque_B_Nm, dtype=float)

    def force_B_N(self, torque_B_Nm: np.ndarray) -> np.ndarray:
        """F_B = P T (eq. 9): the body force that comes with torque T."""
        return self.p @ np.asarray(torque_B_Nm, dtype=float)

    def min_torque_III_Nm(self, t1_Nm: float, t2_Nm: float) -> float:
        """The least axis-III torque with which (T_I, T_II) is made by thrusts ≥ 0 (ii)."""
        f0 = self.m_inv[:, 0] * t1_Nm + self.m_inv[:, 1] * t2_Nm
        g = self.m_inv[:, 2]  # > 0 elementwise under (i)-(ii)
        return max(0.0, float(np.max(-f0 / g)))

    def torque_B_Nm(self, t1_Nm: float, t2_Nm: float, extra_III_Nm: float = 0.0) -> np.ndarray:
        """The torque (T_I, T_II, T_III,min + extra) the three thrusters can make."""
        return np.array([t1_Nm, t2_Nm,
                         self.min_torque_III_Nm(t1_Nm, t2_Nm) + max(0.0, extra_III_Nm)])
