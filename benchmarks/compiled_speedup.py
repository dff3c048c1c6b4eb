"""Speed of the mypyc-compiled hot paths against their own source, as JSON.

For each kernel: the installed (compiled) module and the same module's ``.py`` loaded a
second time as interpreted Python are timed on the same inputs, in turns, within one
run; prints the median µs per call of each and their ratio. The whole-run effect is
``python benchmarks/quickstart_runs.py`` (real-time factor) on a compiled and on a
``THRUSTER_HIL_PURE=1`` install. See ``setup.py`` for what is compiled and why.

    python benchmarks/compiled_speedup.py
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import numpy as np

REPO = Path(__file__).resolve().parent.parent
CALLS = 2000
ROUNDS = 7
US_PER_S = 1e6


def _twins(name: str) -> tuple[ModuleType, ModuleType]:
    compiled = importlib.import_module(name)
    path = REPO / (name.replace(".", "/") + ".py")
    spec = importlib.util.spec_from_file_location(f"_source_of_{name.replace('.', '_')}", path)
    assert spec is not None and spec.loader is not None
    source = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = source  # dataclasses look their module up there
    spec.loader.exec_module(source)
    return compiled, source


def _per_call_us(fn: Callable[[], object]) -> float:
    t0 = time.perf_counter()
    for _ in range(CALLS):
        fn()
    return (time.perf_counter() - t0) / CALLS * US_PER_S


def _kernels() -> dict[str, tuple[Callable[[], object], Callable[[], object]]]:
    rb_c, rb_s = _twins("bench.station.dynamics.rigid_body")
    mp = rb_c.MassProperties(87.0, ((15.95, 0.0, 0.0), (0.0, 72.19, 0.0), (0.0, 0.0, 72.19)))
    state = (1.0, 0.0, 0.0, 0.0, 0.01, -0.02, 0.03, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    w = (1.0, 2.0, 3.0, 0.1, 0.2, 0.3)
    tm_c, tm_s = _twins("bench.wire.timing.classic")
    e2e_c, e2e_s = _twins("dbc.e2e")
    data = bytes(range(8))
    dq_c, dq_s = _twins("flight_sw.dual_quaternion")
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=8), rng.normal(size=8)
    pw_c, pw_s = _twins("flight_sw.modulation.pwpf")
    args = {"km": 4.5, "tm_s": 0.85, "u_on": 0.45, "u_off": 0.15, "min_on_s": 0.002}
    m_c = pw_c.PwpfModulator(pw_c.PwpfParams(**args))
    m_s = pw_s.PwpfModulator(pw_s.PwpfParams(**args))
    return {
        "rk4_step": (
            lambda: rb_c.rk4_step(state, 0.001, w, w, w, mp),
            lambda: rb_s.rk4_step(state, 0.001, w, w, w, mp),
        ),
        "frame_bits": (lambda: tm_c.frame_bits(0x123, data), lambda: tm_s.frame_bits(0x123, data)),
        "frame_crc": (lambda: e2e_c.frame_crc(0x123, data), lambda: e2e_s.frame_crc(0x123, data)),
        "dual_quaternion_multiply": (lambda: dq_c.multiply(a, b), lambda: dq_s.multiply(a, b)),
        "pwpf_on_time": (
            lambda: m_c.on_time_s(0, 0.5, 0.02),
            lambda: m_s.on_time_s(0, 0.5, 0.02),
        ),
    }


def main() -> None:
    out: dict[str, dict[str, float]] = {}
    for name, (compiled, source) in _kernels().items():
        c_us, s_us = [], []
        for _ in range(ROUNDS):  # in turns, so that machine noise hits both alike
            c_us.append(_per_call_us(compiled))
            s_us.append(_per_call_us(source))
        c, s = statistics.median(c_us), statistics.median(s_us)
        out[name] = {
            "compiled_us": round(c, 3),
            "source_us": round(s, 3),
            "speedup": round(s / c, 2),
        }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
