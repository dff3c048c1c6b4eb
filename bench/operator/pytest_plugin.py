"""pytest plugin of thruster-hil: the ``hil_run`` fixture, for timing tests users write.

Registered through the ``pytest11`` entry point ``thruster_hil``, so installing
thruster-hil makes it available in every pytest session (``-p no:thruster_hil`` turns it
off). A test asks for ``hil_run`` and calls it::

    def test_command_latency(hil_run):
        run = hil_run("scenarios/quickstart.toml", duration_s=5)
        assert run.latency("IMU_RATE", "THR_CMD_0").p99_us < 2000

``hil_run(scenario, *, mode, bus, seed, duration_s, fsw_cmd, overrides, timing, fresh)`` starts the
bench and the flight software through :func:`bench.operator.orchestrator.run_scenario` (the bench
in the test process, the flight software as its own process, exactly as
``thruster-hil run`` does) in a fresh run folder under pytest's temporary directory, and
returns a :class:`HilRun`: ``.summary`` (``summary.json`` as a dict), ``.timing`` (a
:class:`~bench.operator.analysis.timing.RunTiming`), ``.latency(src, dst)``, ``.chain()``,
``.message(name)``, ``.bus_load()``, ``.run_dir``.

Where settings come from (first given wins): the keyword argument, the command-line
option, the scenario (seed, duration) or the default. Command-line options:

* ``--hil-bus SPEC``: the bus (default: a private portable bus per run, ``hilbus:`` in a
  private, owner-only ``XDG_RUNTIME_DIR`` of the session, so parallel sessions never
  meet); e.g. ``--hil-bus socketcan:can0`` for real hardware.
* ``--hil-mode lockstep|realtime`` (default lockstep: modelled bus times, deterministic).
* ``--hil-fsw-cmd CMD``: the flight-software command (placeholders as for
  ``thruster-hil run --fsw-cmd``); ``none`` runs the bench alone, for flight software on
  a board attached to ``--hil-bus``.

Lockstep runs are deterministic, so identical lockstep calls within a session share one
run (``fresh=True`` forces a new one); realtime runs never do. Run folders stay under
pytest's ``--basetemp`` (the latest three sessions are kept) for inspection; a failing
assertion shows the folder in the run's ``repr``.

Project rule: timing assertions that gate CI run in lockstep (modelled time); wall-clock
measurements belong in ``benchmarks/``, never in pass/fail tests.
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
import uuid
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cached_property, partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from bench.operator.analysis.records import (
        BusLoad,
        ChainTiming,
        MessageTiming,
        Percentiles,
        TimingOptions,
    )
    from bench.operator.analysis.timing import RunTiming

MODES = ("lockstep", "realtime")
DEFAULT_MODE = "lockstep"
NO_FSW = "none"  # --hil-fsw-cmd none: the bench alone
PRIVATE_CHANNEL_PREFIX = "hil"
PRIVATE_CHANNEL_HEX = 8
PRIVATE_DIR_PREFIX = "thil-"
XDG = "XDG_RUNTIME_DIR"
SOURCE = "hil_run"


def _bad(key: str, value: object, expected: str) -> Exception:
    """A :class:`dbc.errors.ConfigError` naming ``hil_run`` (imported late: the plugin is
    loaded by every pytest session, and ``dbc`` pulls in cantools)."""
    from dbc.errors import ConfigError

    return ConfigError(SOURCE, key, value, expected)


class _Unset:
    """Marker: a keyword argument not given."""

    def __repr__(self) -> str:
        return "<unset>"


UNSET: Any = _Unset()


def pytest_addoption(parser: pytest.Parser) -> None:
    """``--hil-bus``, ``--hil-mode``, ``--hil-fsw-cmd``."""
    g = parser.getgroup("thruster-hil", "thruster-hil bench runs (hil_run fixture)")
    g.addoption(
        "--hil-bus",
        default=None,
        metavar="SPEC",
        help="bus for hil_run, INTERFACE:CHANNEL (default: a private portable bus per run)",
    )
    g.addoption(
        "--hil-mode",
        default=DEFAULT_MODE,
        choices=MODES,
        help=f"run mode for hil_run (default {DEFAULT_MODE})",
    )
    g.addoption(
        "--hil-fsw-cmd",
        default=None,
        metavar="CMD",
        help=f"flight-software command for hil_run; '{NO_FSW}': the bench alone "
        "(default: this project's flight software)",
    )


def pytest_configure(config: pytest.Config) -> None:
    """Check ``--hil-bus`` early, so a typo is a usage error and not a failed test."""
    bus = config.getoption("--hil-bus", default=None)
    if bus:
        from dbc.errors import BusError
        from transport.spec import BusSpec

        try:
            BusSpec.parse(bus)
        except BusError as exc:
            raise pytest.UsageError(f"--hil-bus: {exc}") from None


def pytest_report_header(config: pytest.Config) -> str | None:
    """One header line with the hil_run settings, when they differ from the defaults."""
    bus = config.getoption("--hil-bus", default=None)
    mode = config.getoption("--hil-mode", default=DEFAULT_MODE)
    fsw = config.getoption("--hil-fsw-cmd", default=None)
    if bus is None and mode == DEFAULT_MODE and fsw is None:
        return None
    return f"thruster-hil: hil_run bus={bus or 'private hilbus'} mode={mode} fsw_cmd={fsw}"


@dataclass(frozen=True)
class HilRunOptions:
    """One run as ``hil_run`` starts it (None: the scenario's seed / duration, a private bus)."""

    scenario: Path
    mode: str = DEFAULT_MODE
    bus: str | None = None
    seed: int | None = None
    duration_s: float | None = None
    fsw_cmd: str | None = None  # None: the bench alone
    overrides: tuple[str, ...] = ()  # scenario KEY=VALUE overrides, e.g. bus.bitrate_bps=125000

    def __post_init__(self) -> None:
        if not isinstance(self.scenario, Path) or not self.scenario.is_file():
            raise _bad("scenario", str(self.scenario), "an existing scenario file")
        if self.mode not in MODES:
            raise _bad("mode", self.mode, f"one of {', '.join(MODES)}")
        if self.bus is not None:
            from dbc.errors import BusError
            from transport.spec import BusSpec

            try:
                BusSpec.parse(self.bus)
            except BusError as exc:
                raise _bad("bus", self.bus, f"a bus spec ({exc})") from None
        if self.seed is not None and (
            isinstance(self.seed, bool) or not isinstance(self.seed, int)
        ):
            raise _bad("seed", self.seed, "None or an integer")
        d = self.duration_s
        if d is not None and (
            isinstance(d, bool) or not isinstance(d, (int, float)) or not math.isfinite(d) or d <= 0
        ):
            raise _bad("duration_s", d, "None or a finite number of seconds > 0")
        if self.fsw_cmd is not None and (not isinstance(self.fsw_cmd, str) or not self.fsw_cmd):
            raise _bad("fsw_cmd", self.fsw_cmd, "None or a command line")
        if not isinstance(self.overrides, tuple) or not all(
            isinstance(o, str) and "=" in o for o in self.overrides
        ):
            raise _bad("overrides", self.overrides, "KEY=VALUE strings")


class HilRun:
    """A finished bench run: summary, timing, and shortcuts to the timing measurements."""

    def __init__(
        self,
        run_dir: Path,
        summary: dict[str, Any],
        options: HilRunOptions,
        bus: str,
        timing_options: TimingOptions | None = None,
    ) -> None:
        self.run_dir = run_dir
        self.summary = summary
        self.options = options
        self.bus = bus
        self.timing_options = timing_options

    def __repr__(self) -> str:
        return (
            f"HilRun({self.options.scenario.name}, mode={self.options.mode}, bus={self.bus}, "
            f"run_dir={self.run_dir})"
        )

    @cached_property
    def timing(self) -> RunTiming:
        """The run's timing (frames.csv, chains.csv), measured on demand."""
        from bench.operator.analysis.timing import RunTiming

        return RunTiming.load(self.run_dir, self.timing_options)

    def latency(self, src: str, dst: str) -> Percentiles:
        """Age of ``src`` data at each reception of ``dst``: p50/p99/max in µs and ``n``."""
        return self.timing.latency(src, dst)

    def chain(self) -> ChainTiming:
        """IMU sample -> command -> valve opening percentiles over the control cycles."""
        return self.timing.chain()

    def message(self, name: str) -> MessageTiming:
        """Per-message timing: count, period, jitter, latency, missed cycles, violations."""
        return self.timing.message(name)

    def bus_load(self, window_ms: float | None = None) -> BusLoad:
        """Bus load per window (mean and peak), overall and per node."""
        return self.timing.bus_load(window_ms)


@contextmanager
def _env(name: str, value: str | None) -> Iterator[None]:
    """Set (or leave alone, for None) an environment variable for the block."""
    if value is None:
        yield
        return
    old = os.environ.get(name)
    os.environ[name] = value
    try:
        yield
    finally:
        if old is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = old


class _Session:
    """Per-session state: temporary folders and the cache of lockstep runs."""

    def __init__(self, config: pytest.Config, tmp: pytest.TempPathFactory) -> None:
        self.config = config
        self.tmp = tmp
        self.runs: dict[HilRunOptions, tuple[Path, dict[str, Any], str]] = {}
        self.views: dict[tuple[HilRunOptions, Any], HilRun] = {}
        self._xdg: Path | None = None

    @property
    def private_runtime_dir(self) -> Path:
        """An owner-only runtime directory for the private portable buses.

        A short path in the system temporary directory (not under ``--basetemp``): Unix
        socket paths are limited to about 107 bytes. Removed at the end of the session.
        """
        if self._xdg is None:
            self._xdg = Path(tempfile.mkdtemp(prefix=PRIVATE_DIR_PREFIX))  # mode 0o700
            self.config.add_cleanup(partial(shutil.rmtree, self._xdg, ignore_errors=True))
        return self._xdg


class HilRunner:
    """The callable ``hil_run`` fixture: starts a run and returns a :class:`HilRun`."""

    def __init__(self, session: _Session, search_dirs: list[Path]) -> None:
        self._session = session
        self._search_dirs = search_dirs

    def _resolve(self, scenario: str | os.PathLike[str]) -> Path:
        p = Path(scenario)
        if p.is_absolute():
            return p
        for d in self._search_dirs:
            if (d / p).is_file():
                return (d / p).resolve()
        raise _bad(
            "scenario",
            str(scenario),
            "a scenario file (relative paths are tried in "
            + ", ".join(str(d) for d in self._search_dirs)
            + ")",
        )

    def __call__(
        self,
        scenario: str | os.PathLike[str],
        *,
        mode: str | None = None,
        bus: str | None = None,
        seed: int | None = None,
        duration_s: float | None = None,
        fsw_cmd: str | None = UNSET,
        overrides: Sequence[str] = (),
        timing: TimingOptions | None = None,
        fresh: bool = False,
    ) -> HilRun:
        """Run ``scenario`` (bench + flight software) and return the finished run.

        ``mode``/``bus``: override ``--hil-mode``/``--hil-bus``; ``seed``/``duration_s``:
        override the scenario's; ``fsw_cmd``: the flight-software command (None: the
        bench alone; default ``--hil-fsw-cmd`` or this project's flight software);
        ``overrides``: scenario ``KEY=VALUE`` overrides (``"bus.bitrate_bps=125000"``);
        ``timing``: :class:`~bench.operator.analysis.records.TimingOptions` for the measurements;
        ``fresh``: do not reuse an identical lockstep run of this session.
        """
        from bench.operator.fsw_process import DEFAULT_FSW_CMD

        config = self._session.config
        if fsw_cmd is UNSET:
            opt = config.getoption("--hil-fsw-cmd", default=None)
            fsw_cmd = DEFAULT_FSW_CMD if opt is None else (None if opt == NO_FSW else opt)
        opts = HilRunOptions(
            scenario=self._resolve(scenario),
            mode=mode or config.getoption("--hil-mode", default=DEFAULT_MODE),
            bus=bus or config.getoption("--hil-bus", default=None),
            seed=seed,
            duration_s=duration_s,
            fsw_cmd=fsw_cmd,
            overrides=(overrides,) if isinstance(overrides, str) else tuple(overrides),
        )
        s = self._session
        if opts.mode != "lockstep" or fresh or opts not in s.runs:
            run_dir, summary, used_bus = self._run(opts)
            run = HilRun(run_dir, summary, opts, used_bus, timing)
            if opts.mode == "lockstep":  # the newest run of these options is the shared one
                s.runs[opts] = (run_dir, summary, used_bus)
                for key in [k for k in s.views if k[0] == opts]:
                    del s.views[key]
                s.views[(opts, timing)] = run
            return run
        if (opts, timing) not in s.views:
            s.views[(opts, timing)] = HilRun(*s.runs[opts][:2], opts, s.runs[opts][2], timing)
        return s.views[(opts, timing)]

    def _run(self, opts: HilRunOptions) -> tuple[Path, dict[str, Any], str]:
        """Run once; returns (run folder, summary, bus spec used)."""
        from bench.operator.orchestrator import RunOptions, run_scenario
        from bench.scenario.load import load_scenario

        sc = load_scenario(opts.scenario, list(opts.overrides))
        private = opts.bus is None
        bus = (
            f"hilbus:{PRIVATE_CHANNEL_PREFIX}{uuid.uuid4().hex[:PRIVATE_CHANNEL_HEX]}"
            if private
            else str(opts.bus)
        )
        out = self._session.tmp.mktemp(f"hil_run_{sc.name}") / "run"
        run_opts = RunOptions(
            mode=opts.mode,
            bus=bus,
            seed=sc.seed if opts.seed is None else opts.seed,
            out=out,
            duration_s=sc.duration_s if opts.duration_s is None else opts.duration_s,
            fsw_cmd=opts.fsw_cmd,
        )
        runtime = str(self._session.private_runtime_dir) if private else None
        with _env(XDG, runtime):
            summary = run_scenario(sc, run_opts)
        return out, summary, bus


@pytest.fixture(scope="session")
def hil_session(pytestconfig: pytest.Config, tmp_path_factory: pytest.TempPathFactory) -> _Session:
    """Session state of ``hil_run`` (temporary folders, cache of lockstep runs)."""
    return _Session(pytestconfig, tmp_path_factory)


@pytest.fixture
def hil_run(request: pytest.FixtureRequest, hil_session: _Session) -> HilRunner:
    """Factory: ``hil_run(scenario, mode=..., bus=..., seed=..., duration_s=...)`` -> HilRun.

    Relative scenario paths are tried from the invocation directory, the rootdir, then
    the test file's directory.
    """
    config = request.config
    dirs = [Path(config.invocation_params.dir), Path(config.rootpath), Path(request.path).parent]
    unique = list(dict.fromkeys(d.resolve() for d in dirs))
    return HilRunner(hil_session, unique)
