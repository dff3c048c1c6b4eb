"""OpenBLAS settings of the flight-software process, applied when this module is imported.

What it does: sets two environment variables that OpenBLAS reads once, when numpy first
loads it, so the flight software's entry point imports this before anything imports numpy.
A value the user already set is kept for both.

- ``OPENBLAS_NUM_THREADS=1``: one thread, as on a flight computer. OpenBLAS's worker
  threads (numpy's products of 3×3 and 6×16 matrices) only spin between the cycles, taking
  the core the bench needs (6 % of a lockstep quickstart's CPU).
- ``OPENBLAS_CORETYPE=Prescott`` on x86-64: the same arithmetic on every x86-64 CPU.
  OpenBLAS picks a kernel for the CPU when it loads (Haswell, SkylakeX, Zen, ...) and the
  kernels sum in different orders, so the allocators' set-up (pseudo-inverse, SVDs,
  Riccati) differed in its last bits between machines, and a lockstep trace could with it.
  Its generic x86-64 kernel (Prescott, SSE3) runs on every x86-64 CPU; the flight
  software's matrices are small, so it costs nothing measurable. Other machines keep
  OpenBLAS's own choice.

No frames in or out; no numpy import here.
"""

from __future__ import annotations

import os
import platform

X86_64_MACHINES = ("x86_64", "amd64")
GENERIC_X86_64_KERNEL = "Prescott"

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
if platform.machine().lower() in X86_64_MACHINES:
    os.environ.setdefault("OPENBLAS_CORETYPE", GENERIC_X86_64_KERNEL)
