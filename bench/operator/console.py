"""What a run says on the console: the progress line while it runs, the summary at the end.

In: the simulated time as the run goes; the run's ``summary.json`` content. Out: text on
standard error (progress: a bar on a terminal, a line each 10 % otherwise) and standard
output (the summary: the pointing results, expectations, warnings, the verdict and every
abnormal line, the run folder).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from bench.operator.verdict import abnormal, verdict

BAR_WIDTH = 30


def progress_printer() -> Any:
    tty = sys.stderr.isatty()
    last = [-1.0]

    def show(t_s: float, total_s: float) -> None:
        frac = min(1.0, t_s / total_s) if total_s > 0 else 1.0
        if tty:
            n = int(frac * BAR_WIDTH)
            sys.stderr.write(f"\r[{'#' * n}{'.' * (BAR_WIDTH - n)}] {t_s:7.2f}/{total_s:.2f} s sim")
            sys.stderr.flush()
        elif frac - last[0] >= 0.1 or frac >= 1.0:
            last[0] = frac
            sys.stderr.write(f"progress {frac * 100:5.1f} % ({t_s:.1f}/{total_s:.1f} s sim)\n")

    return show


def _fmt(x: Any, spec: str = ".4f", none: str = "n/a") -> str:
    return none if x is None else format(x, spec)


def _settling_text(settling: float | None) -> str:
    if settling is None:
        return "not settled"
    return f"{settling:.2f} s" + (" (never left the band)" if settling == 0.0 else "")


def _position_text(s: dict[str, Any]) -> str:
    """Position errors where the run has a position reference; else the translation the
    firing caused (an attitude-only run has no position to be in error from)."""
    if s.get("final_position_error_m") is not None:
        return (f"position error final {_fmt(s['final_position_error_m'])} m, steady-state "
                f"{_fmt(s.get('steady_state_position_error_m'))} m")
    tr = s.get("net_translation")
    if not tr:
        return ""
    return (f"translation caused by the firing (attitude only: no position reference) "
            f"{tr['displacement_m']:.3f} m, delta-v {tr['delta_v_m_s'] * 1000:.1f} mm/s")


def print_summary(s: dict[str, Any], out: Path) -> None:
    lat = s["latency_us"]["sensor_to_command"]
    dm = s.get("deadline_misses") or {}
    settling = s["settling_time_s"]
    lines = [
        f"scenario {s['scenario']} | mode {s['mode']} | bus {s['bus']} | seed {s['seed']}",
        f"sim {s['sim_time_s']:.1f} s in {_fmt(s['wall_time_s'], '.2f')} s wall "
        f"(real-time factor {_fmt(s['realtime_factor'], '.1f')})",
        f"converged {s['converged']} | settling "
        f"{_settling_text(settling)} | steady-state error "
        f"{_fmt(s['steady_state_attitude_error_deg'])} deg, "
        f"{_fmt(s['steady_state_rate_error_deg_s'])} deg/s",
        _position_text(s),
        f"propellant {s['propellant_kg'] * 1000:.1f} g | valve openings "
        f"{(s.get('valve_openings') or {}).get('total', 'n/a')}",
        f"latency sensor->command p50 {_fmt(lat['p50'], '.0f')} us, p99 {_fmt(lat['p99'], '.0f')}"
        f" us, max {_fmt(lat['max'], '.0f')} us (n={lat['n']}) | stalls {dm.get('stalls', 0)}, "
        f"flight-software overruns {dm.get('fsw_overruns', 0)}, "
        f"bench late {dm.get('bench_late', 0)}",
    ]
    lines = [x for x in lines if x]
    reqs = s.get("requirements") or {}
    if not s["converged"]:  # a run fails on this alone, with or without expectations
        req = f" [{reqs['converged']}]" if reqs.get("converged") else ""
        lines.append(f"  FAIL converged{req}: the attitude error did not end inside the "
                     f"{_fmt(s.get('settling_band_deg'), 'g')} deg settling band")
    for e in s["expectations"]:
        req = f" [{e['req']}]" if e.get("req") else ""
        lines.append(f"  {'PASS' if e['pass'] else 'FAIL'} {e['name']}{req} = "
                     f"{_fmt(e['value'])} (max {e['max']}"
                     f"{'; ' + e['note'] if e.get('note') else ''})")
    for w in s.get("warnings", []):
        lines.append(f"  WARNING {w}")
    if "error" in s:
        lines.append(f"  ERROR {s['error']}")
    lines.append(f"verdict: {s.get('verdict') or verdict(s)}")
    found = s["abnormal"] if isinstance(s.get("abnormal"), list) else abnormal(s)
    lines += [f"  ABNORMAL {x}" for x in found] or ["  nothing abnormal"]
    lines.append(f"run folder: {out}")
    print("\n".join(lines))
