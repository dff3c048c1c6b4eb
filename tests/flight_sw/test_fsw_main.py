"""The flight-software entry point: a refused configuration exits 2 and says why."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bench.scenario.load import load_scenario
from dbc.contract import EXIT_REFUSED, REFUSAL_SCHEMA, FswRefusal
from flight_sw.__main__ import main

QUICKSTART = Path(__file__).resolve().parents[2] / "scenarios" / "quickstart.toml"


def test_refused_configuration_exits_2_with_the_reason_in_the_stats_file(tmp_path: Path) -> None:
    """A bad modulator kind: exit 2; the --stats file holds a refusal record naming the key
    and the value."""
    cfg = load_scenario(QUICKSTART).fsw_config()
    cfg["flight_sw"]["modulator"]["kind"] = "pwfp"
    config = tmp_path / "fsw_config.json"
    config.write_text(json.dumps(cfg), encoding="utf-8")
    stats = tmp_path / "fsw_stats.json"
    assert main(["--config", str(config), "--stats", str(stats)]) == EXIT_REFUSED
    data = json.loads(stats.read_text(encoding="utf-8"))
    assert data["schema"] == REFUSAL_SCHEMA
    refusal = FswRefusal.from_json(data, str(stats))
    assert refusal.key == "flight_sw.modulator.kind" and refusal.value == "pwfp"
    assert "'pwfp'" in refusal.message


def test_good_configuration_checks_ok_and_writes_no_refusal(tmp_path: Path) -> None:
    """--check on the quickstart's configuration: exit 0, nothing refused."""
    config = tmp_path / "fsw_config.json"
    config.write_text(json.dumps(load_scenario(QUICKSTART).fsw_config()), encoding="utf-8")
    stats = tmp_path / "fsw_stats.json"
    assert main(["--config", str(config), "--check", "--stats", str(stats)]) == 0
    assert not stats.exists()


def test_flight_software_runs_blas_on_one_thread_unless_told_otherwise() -> None:
    """Loading the entry point sets OPENBLAS_NUM_THREADS=1 before numpy loads OpenBLAS
    (asked of the loaded OpenBLAS itself); a value already in the environment is kept."""
    import os
    import subprocess
    import sys

    probe = (
        "import ctypes, os, flight_sw.__main__, numpy\n"
        "path = next(ln.split()[-1] for ln in open('/proc/self/maps')\n"
        "            if 'openblas' in ln and ln.split()[-1].endswith('.so'))\n"
        "lib = ctypes.CDLL(path)\n"
        "names = ('scipy_openblas_get_num_threads64_', 'openblas_get_num_threads64_',\n"
        "         'openblas_get_num_threads')\n"
        "get = next(getattr(lib, n) for n in names if hasattr(lib, n))\n"
        "print(os.environ['OPENBLAS_NUM_THREADS'], get())\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    out = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True,
                         text=True, check=True).stdout.split()
    assert out == ["1", "1"]
    out = subprocess.run([sys.executable, "-c", probe], env={**env, "OPENBLAS_NUM_THREADS": "2"},
                         capture_output=True, text=True, check=True).stdout.split()
    assert out[0] == "2"


def test_flight_software_pins_the_generic_blas_kernel_unless_told_otherwise() -> None:
    """On x86-64, loading the entry point makes OpenBLAS load its generic kernel (Prescott:
    the same arithmetic on every x86-64 CPU), asked of the loaded OpenBLAS itself; a
    kernel already asked for in the environment (Haswell, where the CPU has AVX2) is kept."""
    import os
    import platform
    import subprocess
    import sys

    from flight_sw.blas_env import GENERIC_X86_64_KERNEL, X86_64_MACHINES

    if platform.machine().lower() not in X86_64_MACHINES:
        pytest.skip(f"not x86-64 ({platform.machine()}): OpenBLAS's kernel is left alone")
    probe = (
        "import ctypes, os, flight_sw.__main__, numpy\n"
        "path = next(ln.split()[-1] for ln in open('/proc/self/maps')\n"
        "            if 'openblas' in ln and ln.split()[-1].endswith('.so'))\n"
        "lib = ctypes.CDLL(path)\n"
        "names = ('scipy_openblas_get_corename64_', 'openblas_get_corename64_',\n"
        "         'openblas_get_corename')\n"
        "get = next(getattr(lib, n) for n in names if hasattr(lib, n))\n"
        "get.restype = ctypes.c_char_p\n"
        "print(os.environ['OPENBLAS_CORETYPE'], get().decode())\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}

    def loaded(coretype: str | None) -> list[str]:
        extra = {} if coretype is None else {"OPENBLAS_CORETYPE": coretype}
        return subprocess.run([sys.executable, "-c", probe], env={**env, **extra},
                              capture_output=True, text=True, check=True).stdout.split()

    # (OpenBLAS names the kernel it loads for "Prescott" by its own table: "Katmai" here)
    assert loaded(None) == loaded(GENERIC_X86_64_KERNEL)
    assert loaded(None)[0] == GENERIC_X86_64_KERNEL
    if " avx2 " in Path("/proc/cpuinfo").read_text():  # a kernel this CPU can run
        assert loaded("Haswell") == ["Haswell", "Haswell"] != loaded(None)
