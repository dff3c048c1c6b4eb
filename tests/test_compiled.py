"""The mypyc-compiled modules (``setup.py``'s COMPILED): built, fresh, and bit-identical.

Each compiled module is checked against its own source, loaded a second time as plain
interpreted Python under another name: the same inputs give exactly equal outputs (RK4
states, thruster wrenches, CAN frame lengths, CRCs, dual-quaternion products, PWPF
on-times). Random inputs come from a fixed seed. In a pure-Python install (``THRUSTER_HIL_PURE=1``
in the environment, or no module of COMPILED with an extension on disk: what
``THRUSTER_HIL_PURE=1 pip install -e .`` leaves, since it removes stale ones) nothing is
compiled and the freshness checks are skipped; the comparisons then hold trivially. Some
modules compiled and others not is a broken build and fails.
"""

from __future__ import annotations

import ast
import importlib
import importlib.machinery
import importlib.util
import os
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

REPO = Path(__file__).resolve().parent.parent
SEED = 20261202
CASES = 200
PURE = os.environ.get("THRUSTER_HIL_PURE") == "1"


def _compiled_paths() -> list[str]:
    tree = ast.parse((REPO / "setup.py").read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "COMPILED":
            value = ast.literal_eval(node.value)
            assert isinstance(value, list)
            return [str(p) for p in value]
    raise AssertionError("setup.py has no COMPILED list")


COMPILED = _compiled_paths()


def _module_name(path: str) -> str:
    return path.removesuffix(".py").replace("/", ".")


def _found_origin(path: str) -> Path | None:
    """What the import system finds on disk for the module at ``path`` (not sys.modules: a
    module imported by another compiled one has a synthetic __spec__ and __file__)."""
    source = REPO / path
    spec = importlib.machinery.PathFinder.find_spec(_module_name(path), [str(source.parent)])
    return None if spec is None or spec.origin is None else Path(spec.origin)


def _is_extension(origin: Path | None) -> bool:
    return origin is not None and origin.name.endswith(
        tuple(importlib.machinery.EXTENSION_SUFFIXES))


# a pure install: said so, or not one listed module has an extension
PURE_REASON = (
    "THRUSTER_HIL_PURE=1: a pure-Python install" if PURE
    else None if any(_is_extension(_found_origin(p)) for p in COMPILED)
    else "a pure-Python install: no module of setup.py's COMPILED has a compiled extension "
    "(`pip install -e .` without THRUSTER_HIL_PURE=1 builds them)"
)


def _source_twin(name: str) -> ModuleType:
    """The module ``name`` interpreted from its ``.py`` (dependencies as installed)."""
    path = REPO / (name.replace(".", "/") + ".py")
    spec = importlib.util.spec_from_file_location(f"_source_of_{name.replace('.', '_')}", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("path", COMPILED)
def test_compiled_module_is_built_and_fresh(path: str) -> None:
    """Each listed module imports as an extension no older than its source."""
    if PURE_REASON is not None:
        pytest.skip(PURE_REASON)
    source = REPO / path
    built = _found_origin(path)
    assert built is not None, f"{path}: not importable"
    assert _is_extension(built), (
        f"{path}: not compiled ({built}) while other modules are; run `pip install -e .`")
    assert built.stat().st_mtime >= source.stat().st_mtime, (
        f"{path} changed after {built.name} was built: rerun `pip install -e .`"
    )


def test_rk4_step_matches_source() -> None:
    """Compiled RK4 steps equal the interpreted ones exactly on random states."""
    compiled = importlib.import_module("bench.station.dynamics.rigid_body")
    source = _source_twin("bench.station.dynamics.rigid_body")
    rng = np.random.default_rng(SEED)
    j = np.diag([15.95, 72.19, 72.19]) + 0.5 * np.array([[0, 1, 0], [1, 0, 0], [0, 0, 0]])
    mp = compiled.MassProperties(87.0, tuple(tuple(float(x) for x in r) for r in j))
    for _ in range(CASES):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        state = tuple(float(x) for x in (*q, *rng.normal(size=9)))
        w0, wm, w1 = (tuple(float(x) for x in rng.normal(size=6)) for _ in range(3))
        dt_s = float(rng.uniform(1e-4, 1e-2))
        assert compiled.rk4_step(state, dt_s, w0, wm, w1, mp) == source.rk4_step(
            state, dt_s, w0, wm, w1, mp
        )


def test_frame_bits_and_crc_match_source() -> None:
    """Stuffed CAN frame lengths and E2E CRCs equal the interpreted ones on random frames."""
    timing = importlib.import_module("bench.wire.timing.classic")
    timing_src = _source_twin("bench.wire.timing.classic")
    e2e = importlib.import_module("dbc.e2e")
    e2e_src = _source_twin("dbc.e2e")
    rng = np.random.default_rng(SEED)
    for _ in range(CASES):
        can_id = int(rng.integers(0, 0x800))
        data = bytes(rng.integers(0, 256, size=int(rng.integers(0, 9)), dtype=np.uint8))
        assert timing.frame_bits(can_id, data) == timing_src.frame_bits(can_id, data)
        assert e2e.frame_crc(can_id, data) == e2e_src.frame_crc(can_id, data)


def test_dual_quaternion_product_matches_source() -> None:
    """Compiled dual-quaternion products equal the interpreted ones exactly."""
    compiled = importlib.import_module("flight_sw.dual_quaternion")
    source = _source_twin("flight_sw.dual_quaternion")
    rng = np.random.default_rng(SEED)
    for _ in range(CASES):
        a, b = rng.normal(size=8), rng.normal(size=8)
        assert np.array_equal(compiled.multiply(a, b), source.multiply(a, b))


def test_pwpf_on_times_match_source() -> None:
    """A compiled PWPF modulator gives the interpreted one's on-times, cycle by cycle."""
    compiled = importlib.import_module("flight_sw.modulation.pwpf")
    source = _source_twin("flight_sw.modulation.pwpf")
    args = {"km": 4.5, "tm_s": 0.85, "u_on": 0.45, "u_off": 0.15, "min_on_s": 0.002}
    mod_c = compiled.PwpfModulator(compiled.PwpfParams(**args))
    mod_s = source.PwpfModulator(source.PwpfParams(**args))
    rng = np.random.default_rng(SEED)
    period_s, period_ns = 0.02, 20_000_000
    for k in range(CASES):
        u = float(rng.uniform(-0.2, 1.2))
        assert mod_c.on_time_s(k * period_ns, u, period_s) == mod_s.on_time_s(
            k * period_ns, u, period_s
        )


def test_rls_kernel_matches_source() -> None:
    """Compiled RLS window equations and steps equal the interpreted ones exactly."""
    compiled = importlib.import_module("flight_sw.estimation.rls_kernel")
    source = _source_twin("flight_sw.estimation.rls_kernel")
    rng = np.random.default_rng(SEED)
    window = 5
    for _ in range(CASES):
        h_s = rng.uniform(0.019, 0.021, size=window).tolist()
        omega = rng.normal(size=(window + 1, 3)).tolist()
        gyro = [compiled.gyroscopic(w) for w in omega]
        assert gyro == [source.gyroscopic(w) for w in omega]
        tau = rng.normal(size=(window, 3)).tolist()
        phi, y = compiled.window_equation(h_s, omega[0], omega[-1], gyro, tau)
        assert (phi, y) == source.window_equation(h_s, omega[0], omega[-1], gyro, tau)
        a = rng.normal(size=(6, 6))
        p = (a @ a.T).tolist()
        theta = rng.normal(size=6).tolist()
        args = (p, theta, np.eye(6).tolist(), phi, y, 0.99, 10.0)
        assert compiled.rls_step(*args) == source.rls_step(*args)


def test_mekf_kernel_matches_source() -> None:
    """Compiled MEKF covariance propagation and update equal the interpreted ones exactly."""
    compiled = importlib.import_module("flight_sw.estimation.mekf_kernel")
    source = _source_twin("flight_sw.estimation.mekf_kernel")
    rng = np.random.default_rng(SEED)
    for _ in range(CASES):
        a = rng.normal(size=(6, 6))
        p = (a @ a.T).ravel().tolist()
        phi11, phi12 = rng.normal(size=9).tolist(), rng.normal(size=9).tolist()
        args = (p, phi11, phi12, 1e-10, -1e-14, 1e-16)
        assert compiled.propagate_covariance(*args) == source.propagate_covariance(*args)
        y = rng.normal(size=3).tolist()
        assert compiled.star_tracker_update(p, 0.5, y) == source.star_tracker_update(p, 0.5, y)


def test_residual_kernel_matches_source() -> None:
    """Compiled residual-FDIR window, hypotheses and signature equal the interpreted ones."""
    compiled = importlib.import_module("flight_sw.fdir.residual_kernel")
    source = _source_twin("flight_sw.fdir.residual_kernel")
    rng = np.random.default_rng(SEED)
    n, samples, noise = 8, 12, [1e-4, 0.05, 0.05, 1e-3, 5e-3, 1e-3]
    for _ in range(CASES):
        ang, lin = rng.normal(size=(3, n)).tolist(), rng.normal(size=(3, n)).tolist()
        j = (np.eye(3) * 10.0).tolist()
        j_inv = (np.eye(3) * 0.1).tolist()
        fs, frac = rng.normal(size=(samples, 3)).tolist(), rng.uniform(size=(samples, n)).tolist()
        rate = rng.uniform(size=(samples, n)).tolist()
        terms = [compiled.sample_terms(fs[s], frac[s], rate[s], lin, noise)
                 for s in range(samples)]
        assert terms == [source.sample_terms(fs[s], frac[s], rate[s], lin, noise)
                         for s in range(samples)]
        args = (ang, lin, j, j_inv, rng.uniform(size=n).tolist(), [1.0] * n,
                rng.normal(size=3).tolist(), rng.normal(size=3).tolist(), 0.5, fs,
                [t for t, _ in terms], frac, [0.0, 0.0, 0.0], 0.01, noise)
        out = compiled.window_residual(*args)
        assert out == source.window_residual(*args)
        z, h_ang, h_lin, u_s, w_lin, _ = out
        stuck, known = [k == 1 for k in range(n)], [k == 2 for k in range(n)]
        hyp = (z, h_ang, args[4], 0.5, frac, stuck, w_lin, [i for _, i in terms], lin, known,
               1.1)
        assert compiled.hypotheses(*hyp) == source.hypotheses(*hyp)
        sig = (3, h_ang, h_lin, args[4], 0.5, u_s, stuck, samples, 0.01)
        assert compiled.signature(*sig) == source.signature(*sig)
