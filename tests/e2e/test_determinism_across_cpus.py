"""One lockstep run gives one trace whichever BLAS kernel the machine's CPU gets (OpenBLAS).

OpenBLAS loads a kernel for the CPU (Haswell, SkylakeX, Zen, ...) and the kernels sum in
different orders. The flight software pins the generic x86-64 kernel for itself (its entry
point; ``tests/flight_sw/test_fsw_main.py`` checks that), and its per-cycle arithmetic and
the bench's are plain floats. Here each shipped scenario runs twice: once as on any
machine (the bench on this CPU's own kernel) and once with the generic kernel forced on
both sides, as on a CPU that has nothing newer; the traces must be the same.
"""

from __future__ import annotations

import ctypes
import platform
from pathlib import Path

import numpy as np
import pytest

from flight_sw.blas_env import GENERIC_X86_64_KERNEL, X86_64_MACHINES
from tests.e2e.conftest import REPO, run_cli, unique_bus

pytestmark = pytest.mark.slow

SCENARIOS = sorted((REPO / "scenarios").glob("*.toml"))
CORENAME_FUNCTIONS = ("scipy_openblas_get_corename64_", "openblas_get_corename64_",
                      "openblas_get_corename")


def _own_kernel() -> str | None:
    """The kernel this process's OpenBLAS loaded (None: numpy's BLAS is not OpenBLAS)."""
    np.ones((2, 2)) @ np.ones((2, 2))
    maps = Path("/proc/self/maps")
    if not maps.exists():
        return None
    paths = [ln.split()[-1] for ln in maps.read_text().splitlines()
             if "openblas" in ln and ln.split()[-1].endswith(".so")]
    if not paths:
        return None
    lib = ctypes.CDLL(paths[0])
    get = next((getattr(lib, n) for n in CORENAME_FUNCTIONS if hasattr(lib, n)), None)
    if get is None:
        return None
    get.restype = ctypes.c_char_p
    return str(get().decode())


@pytest.mark.parametrize("scenario", SCENARIOS, ids=[p.stem for p in SCENARIOS])
def test_trace_is_the_same_on_the_cpus_kernel_and_the_generic_one(
    scenario: Path, tmp_path: Path, runtime_dir: Path
) -> None:
    """A shipped scenario's whole lockstep run gives one trace digest with the bench on this
    CPU's OpenBLAS kernel and with the generic kernel forced on both processes."""
    if platform.machine().lower() not in X86_64_MACHINES:
        pytest.skip(f"not x86-64 ({platform.machine()})")
    own = _own_kernel()
    if own is None:
        pytest.skip("numpy's BLAS is not OpenBLAS: no kernel to compare")
    digests = {}
    # "cpu": no OPENBLAS_CORETYPE (as on a user's machine; this one may set it)
    for label, env in (("cpu", {}), ("generic", {"OPENBLAS_CORETYPE": GENERIC_X86_64_KERNEL})):
        r = run_cli(
            ["run", str(scenario), "--bus", unique_bus(), "--seed", "7", "--record", "lean",
             "--no-plots"],
            tmp_path / label, runtime_dir, extra_env=env, drop_env=("OPENBLAS_CORETYPE",),
        )
        assert r.returncode == 0, r.stderr
        digests[label] = r.summary["trace_sha256"]
    assert digests["cpu"] == digests["generic"], (own, digests)
