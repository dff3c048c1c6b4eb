"""One lockstep run gives one trace whichever BLAS kernel the CPU gets (OpenBLAS)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.e2e.conftest import REPO, run_cli, unique_bus

pytestmark = pytest.mark.slow

SCENARIOS = sorted((REPO / "scenarios").glob("*.toml"))
# OpenBLAS's kernel choice, forced, with the CPU flags each needs: the generic SSE3 kernel
# runs on every x86-64 CPU; Haswell (AVX2, FMA) and SkylakeX (AVX-512) sum in other orders.
# formation_keeping_nftsm's trace differed between Haswell and SkylakeX at 29.5 s while the
# MEKF's covariance went through numpy's BLAS.
KERNELS = (("Prescott", ()), ("Haswell", ("avx2", "fma")), ("SkylakeX", ("avx512f",)))
MIN_KERNELS = 2


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


@pytest.mark.parametrize("scenario", SCENARIOS, ids=[p.stem for p in SCENARIOS])
def test_trace_is_the_same_on_every_blas_kernel(
    scenario: Path, tmp_path: Path, runtime_dir: Path
) -> None:
    """A shipped scenario's whole lockstep run gives one trace digest with OpenBLAS forced to
    each kernel this CPU can run (the flight software's per-cycle arithmetic avoids BLAS)."""
    if "openblas" not in _blas_name():
        pytest.skip(f"numpy's BLAS is {_blas_name()!r}, not OpenBLAS: no kernel to force")
    flags = _cpu_flags()
    kernels = [name for name, needs in KERNELS if set(needs) <= flags]
    if len(kernels) < MIN_KERNELS:
        pytest.skip(f"this CPU runs only OpenBLAS kernels {kernels}: nothing to compare")
    digests = {}
    for core in kernels:
        r = run_cli(
            ["run", str(scenario), "--bus", unique_bus(), "--seed", "7", "--record", "lean",
             "--no-plots"],
            tmp_path / core, runtime_dir, extra_env={"OPENBLAS_CORETYPE": core},
        )
        assert r.returncode == 0, r.stderr
        digests[core] = r.summary["trace_sha256"]
    assert len(set(digests.values())) == 1, digests
