"""One lockstep run gives one trace whichever BLAS kernel the CPU gets (OpenBLAS)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.e2e.conftest import REPO, run_cli, unique_bus

pytestmark = pytest.mark.slow

SCENARIO = REPO / "scenarios" / "formation_keeping_nftsm.toml"
# Long enough to pass 29.5 s, where the MEKF's numpy covariance first changed a valve
# command between the Haswell and SkylakeX kernels.
DURATION_S = "40"
# OpenBLAS's kernel choice, forced: the generic SSE3 kernel runs on every x86-64 CPU, the
# Haswell one (AVX2 and FMA, other summation orders) on the CPUs that have those.
GENERIC, AVX2_FMA = "Prescott", "Haswell"
CPU_FLAGS_NEEDED = ("avx2", "fma")


def _blas_name() -> str:
    cfg = np.show_config(mode="dicts")
    return str(cfg["Build Dependencies"]["blas"]["name"]).lower()


def _cpu_flags() -> set[str]:
    cpuinfo = Path("/proc/cpuinfo")
    if not cpuinfo.exists():
        return set()
    for line in cpuinfo.read_text().splitlines():
        if line.startswith("flags"):
            return set(line.split(":", 1)[1].split())
    return set()


def test_trace_is_the_same_on_two_blas_kernels(tmp_path: Path, runtime_dir: Path) -> None:
    """The same scenario and seed give the same trace digest with OpenBLAS forced to two
    different CPU kernels (the flight software's arithmetic does not go through BLAS)."""
    if "openblas" not in _blas_name():
        pytest.skip(f"numpy's BLAS is {_blas_name()!r}, not OpenBLAS: no kernel to force")
    if not set(CPU_FLAGS_NEEDED) <= _cpu_flags():
        pytest.skip(f"this CPU lacks {CPU_FLAGS_NEEDED}: OpenBLAS's {AVX2_FMA} kernel would fault")
    digests = {}
    for core in (GENERIC, AVX2_FMA):
        r = run_cli(
            ["run", str(SCENARIO), "--bus", unique_bus(), "--duration", DURATION_S,
             "--seed", "7", "--record", "lean", "--no-plots"],
            tmp_path / core, runtime_dir, extra_env={"OPENBLAS_CORETYPE": core},
        )
        assert r.returncode == 0, r.stderr
        digests[core] = r.summary["trace_sha256"]
    assert digests[GENERIC] == digests[AVX2_FMA], digests
