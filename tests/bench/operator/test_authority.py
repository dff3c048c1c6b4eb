"""Control authority: the signed axes a thruster set cannot reach with thrusts T >= 0."""

from __future__ import annotations

from pathlib import Path

from bench.operator.authority import authority_warnings, effectiveness, unreached_axes
from bench.scenario.load import load_scenario

QUICKSTART = Path(__file__).resolve().parents[3] / "scenarios" / "quickstart.toml"


def test_one_thruster_reaches_one_signed_axis() -> None:
    """r = +y, d = +x: torque r × d = −z only; force +x only."""
    b = effectiveness([(0.0, 1.0, 0.0)], [(1.0, 0.0, 0.0)])
    assert unreached_axes(b[3:]) == ["+x", "-x", "+y", "-y", "+z"]
    assert unreached_axes(b[:3]) == ["-x", "+y", "-y", "+z", "-z"]


def test_seed003_set_has_full_torque_authority_and_losing_yaw_is_warned() -> None:
    """Quickstart's 8 thrusters reach every torque axis; without those giving z torque, ±z."""
    sc = load_scenario(QUICKSTART)
    r = [t.r_thr_B_m for t in sc.thrusters]
    d = [t.d_thr_B for t in sc.thrusters]
    assert authority_warnings(r, d, needs_force=False) == []
    b = effectiveness(r, d)
    keep = [k for k in range(len(r)) if abs(b[5, k]) < 1e-12]  # no z torque
    assert keep and len(keep) < len(r)
    (w,) = authority_warnings([r[k] for k in keep], [d[k] for k in keep], needs_force=False)
    assert "cannot produce torque about/along +z, -z" in w
