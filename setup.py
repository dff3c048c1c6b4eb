"""Build hook: compiles the hot-path modules to C extensions with mypyc.

What and why
    The modules in :data:`COMPILED` (bench: rigid-body RK4 (also with HCW translation and
    environment wrenches), disturbance and gravity-gradient models, valves and thruster
    set, CAN bit timing, plant, sensors, the bench loop, recorder; dbc: E2E CRC, signal
    packing, frame encoding and checks; flight_sw: 3-vector algebra, quaternions, dual
    quaternions, the pose laws' error state, NFTSM and TSM, the anti-unwinding error,
    PWPF, the dense solver (Cholesky, Jacobi SVD) and the allocators' box-QP and
    least-squares kernels, the RLS identifier's kernel, the FDIR's expected-thrust
    model) are plain, fully typed Python.
    mypyc (mypy's compiler, https://mypyc.readthedocs.io) turns each into a C extension
    that Python imports instead of the ``.py`` beside it; the arithmetic is the same IEEE
    double arithmetic in the same order (no fused multiply-add on the x86-64 baseline), so
    results are bit-identical (``tests/test_compiled.py`` checks compiled against the
    source on known inputs). ``benchmarks/compiled_speedup.py`` measures the gain.

Pure-Python install
    ``THRUSTER_HIL_PURE=1 pip install -e .`` builds nothing: every module runs from its
    source, with the same results, only slower. Also the way to develop one of these
    modules without rebuilding after each edit. Python prefers an extension beside a
    ``.py`` of the same name, so a pure install first removes the extensions an earlier
    compiled install left in the source tree (each module of :data:`COMPILED` and the
    packages' shared ``compiled__mypyc`` libraries) and names each one on stderr (pip
    shows it with ``-v``); otherwise every edit of those modules would be silently
    ignored. ``tests/test_compiled.py`` skips its freshness checks when no module of
    :data:`COMPILED` has an extension.

Rules for a compiled module (what differs from the interpreter, each met in this code)
    - A frozen configuration dataclass that validates its own fields is marked
      ``@mypyc_attr(native_class=False)``, and ``__post_init__`` reads a field it checks
      the shape of with ``getattr`` (a compiled read casts to the declared type first, so
      a 2-vector would raise TypeError instead of the ConfigError naming it).
    - No identity tests on values (``f is not win`` on tuples, ``value is mass`` on
      floats): compiled tuples and floats are unboxed, so compare by value.
    - A name keeps one type in a function: compiled code enforces the type mypy inferred
      at its first binding (a loop variable that was a ``Delivery`` cannot later be the
      ``None`` of an ``Any``-typed tuple).
    - Native classes cannot be monkeypatched; a class that tests (or users) extend is
      marked ``@mypyc_attr(allow_interpreted_subclasses=True)`` and extended by subclassing.

Editing a compiled module
    The extension shadows the source: after editing a module of :data:`COMPILED`, rerun
    ``pip install -e .`` (``tests/test_compiled.py`` fails, naming the module, while an
    extension is older than its source).
"""

from __future__ import annotations

import importlib.machinery
import os
import sys
from pathlib import Path

from setuptools import setup

COMPILED = [
    "bench/station/dynamics/rigid_body.py",
    "bench/station/dynamics/stepper.py",
    "bench/station/dynamics/translation.py",
    "bench/station/dynamics/hcw.py",
    "bench/station/environment/disturbance.py",
    "bench/station/environment/gravity_gradient.py",
    "bench/station/valves/params.py",
    "bench/station/valves/thrust_profile.py",
    "bench/station/valves/valve.py",
    "bench/station/valves/geometry.py",
    "bench/station/valves/thruster_set.py",
    "bench/wire/timing/classic.py",
    "bench/wire/timing/fd.py",
    "bench/wire/timing/arbiter.py",
    "bench/wire/timing/load.py",
    "dbc/e2e.py",
    "dbc/layout.py",
    "dbc/codec.py",
    "bench/station/plant.py",
    "bench/station/sensors/gyro.py",
    "bench/station/sensors/accelerometer.py",
    "bench/station/sensors/star_tracker.py",
    "bench/node.py",
    "bench/lockstep.py",
    "bench/realtime.py",
    "bench/station/station.py",
    "bench/station/sampling.py",
    "bench/station/fault_book.py",
    "bench/wire/wire.py",
    "bench/wire/receipt.py",
    "bench/wire/fate.py",
    "bench/results/telemetry.py",
    "bench/results/run.py",
    "bench/results/fsw_view.py",
    "bench/wire/trace.py",
    "bench/results/writers.py",
    "flight_sw/vec3.py",
    "flight_sw/quaternion.py",
    "flight_sw/dual_quaternion.py",
    "flight_sw/modulation/pwpf.py",
    "flight_sw/control/anti_unwinding.py",
    "flight_sw/control/dq_error_state.py",
    "flight_sw/control/nftsm_dq.py",
    "flight_sw/control/tsm_dq.py",
    "flight_sw/allocation/dense.py",
    "flight_sw/allocation/dense_active_set.py",
    "flight_sw/estimation/rls_kernel.py",
    "flight_sw/estimation/mekf_kernel.py",
    "flight_sw/fdir/thrust_model.py",
    "flight_sw/fdir/residual_kernel.py",
]
PURE_ENV = "THRUSTER_HIL_PURE"
PACKAGES = ("bench", "dbc", "flight_sw")
SHARED_LIBRARY = "compiled__mypyc"  # mypyc's library of a group, one per package


def stale_extensions(root: Path) -> list[Path]:
    """The compiled modules of :data:`COMPILED` and the groups' shared libraries found
    in the source tree at ``root`` (what a compiled install left beside the sources)."""
    found: list[Path] = []
    stems = [Path(p).with_suffix("") for p in COMPILED]
    stems += [Path(pkg) / SHARED_LIBRARY for pkg in PACKAGES]
    for stem in stems:
        folder = root / stem.parent
        if folder.is_dir():
            found += sorted(p for p in folder.iterdir() if p.name.startswith(stem.name + ".")
                            and p.name.endswith(tuple(importlib.machinery.EXTENSION_SUFFIXES)))
    return found


def remove_stale_extensions(root: Path) -> list[Path]:
    """Remove :func:`stale_extensions` under ``root``, saying so on stderr; returns them."""
    removed = stale_extensions(root)
    for path in removed:
        path.unlink()
        print(f"thruster-hil pure install: removed {path.relative_to(root)} (a compiled "
              "module of an earlier install would shadow its source)", file=sys.stderr)
    return removed


def _ext_modules() -> list:
    if os.environ.get(PURE_ENV) == "1":
        remove_stale_extensions(Path(__file__).resolve().parent)
        return []
    from mypyc.build import mypycify

    # one group (shared library) per top-level package, inside that package: flight_sw
    # and bench never share compiled code, and an editable install can import each one
    groups = [
        ([p for p in COMPILED if p.startswith(f"{pkg}/")], f"{pkg}.compiled")
        for pkg in PACKAGES
    ]
    # the build sees only the source (pip's isolated build has none of the dependencies,
    # so their types are Any there): the same code with or without a developer's cache
    options = ["--no-warn-unused-ignores", f"--cache-dir={os.devnull}"]
    return mypycify([*options, *COMPILED], opt_level="3", separate=groups)


setup(ext_modules=_ext_modules())
