"""Runs one scenario: the bench in this process, the flight software as a child process.

The flight software is started by command (``--fsw-cmd``, ours by default), exactly as a
real bench starts someone else's flight-software binary, so the bench never imports it.
Placeholders in the command: ``{bus}``, ``{mode}``, ``{config}`` (the flight-software
configuration JSON written into the run folder), ``{stats}`` (where it may write its
statistics JSON), ``{rx_log}`` (where it may log when each frame arrived, realtime:
``fsw_rx.csv``, see :mod:`bench.operator.analysis.reception`) and ``{run_dir}``. The run folder
always ends up with ``summary.json``, ``trace.asc``, ``telemetry.csv``,
``valve_pulses.csv``, ``events.jsonl``, ``fsw.log`` and the PNG plots, even when the flight
software dies.
"""

from __future__ import annotations

import ctypes
import gc
import json
import os
import selectors
import shlex
import shutil
import signal
import string
import subprocess
import sys
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bench.node import BenchNode
from bench.operator.analysis.reception import RX_LOG_FILE
from bench.operator.authority import WRENCH_CONTROLLERS, authority_warnings
from bench.operator.plausibility import mass_warnings
from bench.results.counts import frame_table, merge_counts, zero_unheard
from bench.results.metrics import pointing_metrics
from bench.results.writers import write_summary
from bench.scenario.spec import Scenario
from dbc.codec import cycle_time_ns
from dbc.contract import EXIT_REFUSED, REFUSAL_SCHEMA, FswRefusal
from dbc.database import load_database
from dbc.errors import ConfigError, RefusedConfigError, RunError
from dbc.icd import Icd
from transport.hilbus import MEMBER_STALL_S
from transport.lockstep import available_cpus, lockstep_spin_s
from transport.spec import mode_options, open_bus

DEFAULT_FSW_CMD = (
    f"{shlex.quote(sys.executable)} -m flight_sw --bus {{bus}} --mode {{mode}} "
    "--config {config} --stats {stats} --rx-log {rx_log}"
)
FSW_TERM_TIMEOUT_S = 5.0
EXIT_CHILD_OK, EXIT_CHILD_RUN_ERROR, EXIT_CHILD_CRASH, EXIT_CHILD_BAD_INPUT = 0, 3, 4, 5
EXIT_CHILD_INTERRUPTED = 6  # Ctrl-C: the run folder is complete, the parent re-raises it
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


@dataclass(frozen=True)
class RunOptions:
    """How to run a scenario."""

    mode: str
    bus: str
    seed: int
    out: Path
    duration_s: float
    fsw_cmd: str | None = DEFAULT_FSW_CMD  # None: bench alone (external flight software)

    def __post_init__(self) -> None:
        if self.mode not in ("lockstep", "realtime"):
            raise ConfigError("command line", "--mode", self.mode, "lockstep or realtime")
        period_s = cycle_time_ns(load_database(), "THR_CMD_0") / 1e9
        if not self.duration_s >= period_s:  # also rejects NaN
            raise ConfigError("command line", "--duration", self.duration_s,
                              f"at least one control period ({period_s} s)")


PLACEHOLDERS = ("bus", "mode", "config", "stats", "run_dir", "rx_log")


def _fsw_argv(template: str, opts: RunOptions, config: Path, stats: Path) -> list[str]:
    """The flight software's command line: ``template`` split as a shell would, with its
    placeholders (plain names of :data:`PLACEHOLDERS` only: no attribute, index, format
    or conversion) replaced."""
    values = {"bus": opts.bus, "mode": opts.mode, "config": str(config), "stats": str(stats),
              "run_dir": str(opts.out), "rx_log": str(opts.out / RX_LOG_FILE)}
    allowed = " ".join(f"{{{p}}}" for p in PLACEHOLDERS)
    try:
        args = shlex.split(template)
    except ValueError as exc:
        raise ConfigError("command line", "--fsw-cmd", template,
                          f"a command line a shell can split ({exc})") from exc
    out = []
    for a in args:
        parts = []
        try:
            parsed = list(string.Formatter().parse(a))
        except ValueError as exc:
            raise ConfigError("command line", "--fsw-cmd", template,
                              f"placeholders among {allowed} ({exc}; write {{{{ for a brace)"
                              ) from exc
        for literal, name, spec, conv in parsed:
            parts.append(literal)
            if name is None:
                continue
            if name not in values or spec or conv:
                raise ConfigError("command line", "--fsw-cmd", template,
                                  f"placeholders among {allowed}, as plain names (found "
                                  f"{{{name}{'!' + conv if conv else ''}"
                                  f"{':' + spec if spec else ''}}})")
            parts.append(values[name])
        out.append("".join(parts))
    return out


class Terminated(Exception):  # noqa: N818 - a request, not an error
    """SIGTERM in the bench process: finish the run folder, then exit."""


def _terminate(signum: int, frame: object) -> None:
    raise Terminated(f"signal {signum}")


def _die_with_parent() -> None:
    """In the child: ask Linux for SIGTERM when the bench process dies (even by SIGKILL).

    Elsewhere (macOS) this is a no-op; the flight software then notices the silence itself.
    """
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def _stop(proc: subprocess.Popen[bytes]) -> int | None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(FSW_TERM_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return proc.returncode


def run_scenario(
    sc: Scenario,
    opts: RunOptions,
    progress: Callable[[float, float], None] | None = None,
    ready: Callable[[Path], None] | None = None,
) -> dict[str, Any]:
    """Run ``sc``; returns the summary (also written to ``opts.out/summary.json``).

    The bench runs in a forked child process and this process supervises it, so that the
    run folder is completed (from the files written so far) even if the bench is killed.
    """
    out = opts.out
    if opts.fsw_cmd is not None:
        _fsw_argv(opts.fsw_cmd, opts, out, out)  # a bad placeholder: exit 2 before anything runs
    check_bus(opts.bus)
    spin_s = lockstep_spin_s(available_cpus(), os.environ) if opts.mode == "lockstep" else 0.0
    try:
        out.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(sc.path, out / "scenario.toml")
        config = out / "fsw_config.json"
        config.write_text(json.dumps(sc.fsw_config(), indent=2) + "\n", encoding="utf-8")
    except OSError as exc:
        raise ConfigError("command line", "--out", str(out),
                          f"a folder this user can create and write ({exc.strerror or exc})"
                          ) from exc
    if not hasattr(os, "fork"):  # pragma: no cover - no supervisor where fork is missing
        return _run_bench(sc, opts, progress, ready, config, spin_s)
    pid = os.fork()
    if pid == 0:  # the bench process
        code = EXIT_CHILD_OK
        try:
            _die_with_parent()
            signal.signal(signal.SIGTERM, _terminate)
            (out / "bench.pid").write_text(f"{os.getpid()}\n", encoding="utf-8")
            _run_bench(sc, opts, progress, ready, config, spin_s)
        except ConfigError as exc:
            code = EXIT_CHILD_BAD_INPUT
            if not (out / "summary.json").exists():  # refused before the run: say why
                partial_summary(sc, opts, f"bad input: {exc}", refused=str(exc))
        except RunError:
            code = EXIT_CHILD_RUN_ERROR
        except KeyboardInterrupt:
            code = EXIT_CHILD_INTERRUPTED
        except BaseException as exc:
            code = EXIT_CHILD_CRASH
            if not (out / "summary.json").exists() and not isinstance(exc, KeyboardInterrupt):
                traceback.print_exc()  # nothing else will say what happened
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(code)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)  # the bench handles Ctrl-C itself
    try:
        _, status = os.waitpid(pid, 0)
    finally:
        signal.signal(signal.SIGINT, previous)
    (out / "bench.pid").unlink(missing_ok=True)  # a pid file names a running process only
    if os.WIFSIGNALED(status):
        summary = partial_summary(sc, opts, f"bench process killed by signal {os.WTERMSIG(status)}")
        raise RunError(f"run failed ({summary['error']}); partial run folder: {out}")
    if not (out / "summary.json").exists():  # it failed before its run folder was set up
        summary = partial_summary(
            sc, opts, f"bench process exited with code {os.WEXITSTATUS(status)} before "
            "writing summary.json (see its traceback above)")
        raise RunError(f"run failed ({summary['error']}); partial run folder: {out}")
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    if os.WEXITSTATUS(status) == EXIT_CHILD_INTERRUPTED:
        raise KeyboardInterrupt  # after the bench completed the run folder
    if os.WEXITSTATUS(status) == EXIT_CHILD_BAD_INPUT:
        if summary.get("refused"):
            raise RefusedConfigError("the bench", summary["refused"])
        raise RefusedConfigError("the flight software", summary["fsw"]["refused"])
    if os.WEXITSTATUS(status) != EXIT_CHILD_OK:
        tail = "".join(f"\n  fsw.log: {x}" for x in (summary.get("fsw") or {}).get("log_tail", []))
        raise RunError(f"run failed ({summary.get('error')}); run folder: {out}{tail}")
    return summary


def _run_bench(
    sc: Scenario,
    opts: RunOptions,
    progress: Callable[[float, float], None] | None,
    ready: Callable[[Path], None] | None,
    config: Path,
    spin_s: float = 0.0,
) -> dict[str, Any]:
    """The bench process: run, then write summary.json and plots (whatever happened).

    ``spin_s``: lockstep, how long to poll for the flight software's answer before blocking
    (transport.lockstep.lockstep_spin_s; our flight software works its own out the same way).
    """
    out = opts.out
    stats = out / "fsw_stats.json"
    db = load_database()
    bus = open_bus(opts.bus, **mode_options(opts.bus, opts.mode))
    proc: subprocess.Popen[bytes] | None = None
    node = BenchNode(sc, db, bus, out, opts.mode, opts.seed, opts.bus, progress)
    node.lockstep_spin_s = spin_s
    if ready is not None:
        ready(config)
    error: BaseException | None = None
    try:
        if opts.fsw_cmd is not None:
            log = open(out / "fsw.log", "wb")  # noqa: SIM115 - handed to the child
            env = dict(os.environ, PYTHONUNBUFFERED="1")
            proc = subprocess.Popen(
                _fsw_argv(opts.fsw_cmd, opts, config, stats),
                stdout=log,
                stderr=subprocess.STDOUT,
                env=env,
                preexec_fn=_die_with_parent,
            )
            log.close()
            (out / "fsw.pid").write_text(f"{proc.pid}\n", encoding="utf-8")
            node.fsw_alive = lambda: proc is not None and proc.poll() is None
        # Everything built so far lives for the whole run: keep it out of the cyclic
        # garbage collector's passes. Without this, a full collection over it stops the
        # bench for ~100 ms a few seconds in, which in realtime trips the flight software's
        # sensor watchdog (safe mode) every run.
        gc.collect()
        gc.freeze()
        if opts.mode == "lockstep":
            node.run_lockstep(opts.duration_s)
        else:
            node.run_realtime(opts.duration_s)
    except BaseException as exc:  # keep the run folder whatever happened
        error = exc
    finally:
        fsw_rc = _stop(proc) if proc is not None else None
        (out / "fsw.pid").unlink(missing_ok=True)
        bus.shutdown()
    if isinstance(error, (KeyboardInterrupt, Terminated)):
        node.trace.event(node.plant.t_ns, "run_interrupted",
                         by="SIGINT" if isinstance(error, KeyboardInterrupt) else str(error))
    summary = node.close(opts.duration_s if error is None else node.plant.t_ns / 1e9)
    summary["fsw"] = _fsw_report(stats, fsw_rc, out)
    merge_counts(summary["frames"], summary["rejected_other"], "FSW",
                 summary["fsw"].get("sent", {}), summary["fsw"].get("received", {}))
    fsw_heard = {"FSW"} if "received" in summary["fsw"] else set()
    zero_unheard(summary["frames"], {"BENCH"} | fsw_heard)
    if isinstance(summary["deadline_misses"], dict):
        summary["deadline_misses"]["fsw_overruns"] = max(
            summary["deadline_misses"]["fsw_overruns"], summary["fsw"].get("overruns", 0)
        )
        summary["deadline_misses"]["total"] = sum(
            v for k, v in summary["deadline_misses"].items() if k in ("bench_late", "fsw_overruns")
        )
    summary["compromised"] = compromised(summary)
    summary["warnings"] = (bus_warnings(summary) + duration_warnings(sc, opts.duration_s)
                           + scenario_warnings(sc)
                           + [f"flight software: {w}" for w in summary["fsw"].get("warnings", [])
                              if isinstance(w, str)])
    if error is None and not (summary.get("valve_openings") or {}).get("total"):
        summary["warnings"].append(
            "no valve opened in the whole run: if the vehicle was to move, check the thrust "
            "levels against its inertia and the modulator's thresholds (an on-time too short "
            "for min_on_s or a Schmitt trigger's u_on is never commanded)")
    # hilbus: frames the bench and the flight software could not deliver to a member that
    # stopped reading (each process counts its own)
    bench_drops = getattr(bus, "overrun_drops", 0)
    fsw_drops = int(summary["fsw"].get("bus_overrun_drops", 0) or 0)
    summary["bus_overrun_drops"] = bench_drops + fsw_drops
    if bench_drops + fsw_drops:
        fsw_by_pid = {int(k): int(v) for k, v in
                      (summary["fsw"].get("bus_overrun_drops_by_pid") or {}).items()}
        summary["warnings"].append(overrun_warning(
            getattr(bus, "overrun_drops_by_pid", {}), fsw_by_pid, os.getpid(),
            None if proc is None else proc.pid,
            float(getattr(bus, "member_stall_s", None) or MEMBER_STALL_S)))
    if summary["compromised"] is not None:
        summary["passed"] = False
    if error is not None:
        summary["error"] = f"{type(error).__name__}: {error}"
        if "first frame" in str(error):
            summary["fsw"]["log_tail"] = _log_tail(out / "fsw.log")
            # a refusal is a record in the statistics file (dbc.contract.FswRefusal)
            if fsw_rc == EXIT_REFUSED and summary["fsw"].get("refused"):
                summary["error"] = f"the flight software refused its configuration: " \
                                   f"{summary['fsw']['refused']}"
                error = RefusedConfigError("the flight software", summary["fsw"]["refused"])
        summary["passed"] = False
    write_summary(out / "summary.json", summary)
    _plot(out, sc)
    if error is not None and not isinstance(error, Exception):
        raise error  # KeyboardInterrupt and friends, after the folder is complete
    if isinstance(error, RefusedConfigError):
        raise error
    if error is not None:
        tail = "".join(f"\n  fsw.log: {x}" for x in summary["fsw"].get("log_tail", []))
        raise RunError(f"run failed ({summary['error']}); run folder: {out}{tail}") from error
    return summary


def _plot(out: Path, sc: Scenario) -> None:
    """The run's PNG plots. matplotlib is imported here, after the run: the bench process
    does not carry its heap (tens of thousands of objects the garbage collector would walk)
    while it runs."""
    from bench.operator.plots import plot_run

    plot_run(out, sc.expectations.settling_band_deg)


def overrun_warning(
    from_bench: dict[int, int], from_fsw: dict[int, int], bench_pid: int,
    fsw_pid: int | None, stall_s: float,
) -> str:
    """The warning for frames the portable bus dropped for members that stopped reading.

    ``from_bench``/``from_fsw``: frames each process dropped, by the receiving member's
    pid. Naming the member matters: in realtime the one that stalled is often the bench or
    the flight software itself (a long pause), not a monitor.
    """
    def who(pid: int) -> str:
        if pid == bench_pid:
            return f"the bench (pid {pid})"
        if pid == fsw_pid:
            return f"the flight software (pid {pid})"
        return f"another member (pid {pid}, e.g. a paused can.logger)"

    parts = [f"{n} from the {src} to {who(pid)}"
             for src, table in (("bench", from_bench), ("flight software", from_fsw))
             for pid, n in sorted(table.items())]
    total = sum(from_bench.values()) + sum(from_fsw.values())
    return (f"{total} frames were dropped for bus members that did not read for "
            f"{stall_s * 1000:g} ms ({'; '.join(parts) or 'members unknown'}): only those "
            "members missed them")


def check_bus(spec: str) -> None:
    """Open and close ``spec`` once: a bus that cannot be opened fails here, with its reason.

    Raises :class:`~dbc.errors.BusError` (exit 2 from the CLI) instead of letting the forked
    bench fail where only its exit code is seen.
    """
    open_bus(spec).shutdown()


def scenario_warnings(sc: Scenario) -> list[str]:
    """What the scenario's vehicle cannot do (:mod:`bench.operator.authority`): axes its thrusters
    cannot push about or along, for the degrees of freedom its flight software controls;
    and mass properties that look like a unit slip (:mod:`bench.operator.plausibility`)."""
    controller = (sc.flight_sw.get("controller") or {}).get("kind")
    needs_force = controller in WRENCH_CONTROLLERS or "translation" in sc.flight_sw
    r_thr = [t.r_thr_B_m for t in sc.thrusters]
    out = authority_warnings(r_thr, [t.d_thr_B for t in sc.thrusters], needs_force)
    out += mass_warnings("[vehicle]", sc.actual.mass_kg, sc.actual.inertia_B_kgm2, r_thr)
    if sc.nominal != sc.actual:
        out += mass_warnings("[vehicle.nominal]", sc.nominal.mass_kg,
                             sc.nominal.inertia_B_kgm2, r_thr)
    return out


def duration_warnings(sc: Scenario, duration_s: float) -> list[str]:
    """A run too short for its scenario: the steady-state window holds the transient.

    The window is the last ``steady_state_window_s`` of the run; it should start after the
    manoeuvre's start plus its allowed settling time.

    Also: scheduled faults and events that a shortened run (``--duration``) ends before;
    they never act, and the run's figures are those of a run without them.
    """
    out: list[str] = []
    e = sc.expectations
    settled_s = sc.manoeuvre_start_s + (e.settling_time_s_max or 0.0)
    window_start_s = duration_s - e.steady_state_window_s
    if window_start_s < settled_s:
        out.append(f"the run is {duration_s:g} s: its steady-state window (the last "
                   f"{e.steady_state_window_s:g} s) starts before the manoeuvre may have "
                   f"settled ({settled_s:g} s), so steady-state figures include the transient; "
                   f"run at least {settled_s + e.steady_state_window_s:g} s (the scenario's "
                   f"own duration is {sc.duration_s:g} s)")
    for kind, items in (("[[faults]]", sc.faults), ("[[events]]", sc.events)):
        late = [x for x in items if x.t_s >= duration_s]
        if late:
            what = ", ".join(
                f"{getattr(x, 'kind', 'capture')} at {x.t_s:g} s" for x in late)
            out.append(f"the run is {duration_s:g} s: {len(late)} of the scenario's {kind} "
                       f"never act ({what}); run longer than {max(x.t_s for x in late):g} s")
    return out


def compromised(summary: dict[str, Any]) -> dict[str, Any] | None:
    """Evidence that a second sender spoke the ICD on this bus, or None.

    Each side's evidence (its own messages heard well-formed from another node, alive
    counters gone back, a second different command for one cycle), by message; ``messages``
    names them all. A run with any is compromised: its results may hold another node's
    frames, so it does not pass.
    """
    bench = dict(summary.get("second_sender_evidence") or {})
    fsw = dict((summary.get("fsw") or {}).get("second_sender_evidence") or {})
    names = sorted(set(bench) | set(fsw))
    if not names:
        return None
    return {"messages": names, "evidence": {"BENCH": bench, "FSW": fsw}}


def bus_warnings(summary: dict[str, Any]) -> list[str]:
    """Signs that something else shares the bus: a second sender, stale frames, refused
    restarts."""
    out = []
    comp = summary.get("compromised")
    if comp is not None:
        ev = comp["evidence"]
        counts = ", ".join(f"{n} ({ev['BENCH'].get(n, 0) + ev['FSW'].get(n, 0)})"
                           for n in comp["messages"])
        out.append(f"run compromised: another node sends frames of the ICD on this bus: "
                   f"{counts}. A second bench or flight software, or forged frames? "
                   "Use a bus of your own (--bus).")
    for name, f in summary["frames"].items():
        rej = f.get("rejected") or {}
        if rej.get("stale"):
            out.append(f"{rej['stale']} stale {name} frames (for another cycle, or older "
                       "than the last one taken)")
    refused = int((summary.get("fsw") or {}).get("restarts_refused") or 0)
    if refused:
        out.append(f"the flight software refused {refused} bench restarts (SYNC or "
                   "BENCH_STATUS going back while the bench was live: replayed frames?)")
    if summary.get("fsw_restarts_refused"):
        out.append(f"the bench refused {summary['fsw_restarts_refused']} flight-software "
                   "restarts (FSW_STATUS in BOOT mode while it was live: replayed frames?)")
    return out


def _log_tail(log: Path, lines: int = 5) -> list[str]:
    if not log.exists():
        return []
    return log.read_text(encoding="utf-8", errors="replace").splitlines()[-lines:]


def _fsw_report(stats: Path, rc: int | None, out: Path) -> dict[str, Any]:
    """The flight software's part of summary.json: its exit code, its statistics or its
    refusal (dbc.contract records), and its log's tail when it failed."""
    rep: dict[str, Any] = {"exit_code": rc}
    if stats.exists():
        try:
            data = json.loads(stats.read_text(encoding="utf-8"))
            if isinstance(data, dict) and data.get("schema") == REFUSAL_SCHEMA:
                refusal = FswRefusal.from_json(data, str(stats))
                rep.update(refused=refusal.message, refusal=refusal.to_json())
            elif isinstance(data, dict):
                rep.update(data)
            else:
                rep["stats_error"] = f"{stats}: not a JSON object"
        except (OSError, json.JSONDecodeError, ConfigError) as exc:
            rep["stats_error"] = str(exc)
    else:
        rep["stats_error"] = "flight software wrote no statistics"
    if rc not in (0, None):
        rep["log_tail"] = _log_tail(out / "fsw.log")
    return rep


def _wait_for_fsw_exit(out: Path) -> None:
    """After the bench died: give its flight-software child time to write its statistics."""
    try:
        pid = int((out / "fsw.pid").read_text(encoding="utf-8"))
        fd = os.pidfd_open(pid)
    except (OSError, ValueError, AttributeError):
        return
    try:
        sel = selectors.DefaultSelector()
        sel.register(fd, selectors.EVENT_READ)  # readable when the process has exited
        sel.select(timeout=FSW_TERM_TIMEOUT_S)
        sel.close()
    finally:
        os.close(fd)


def partial_summary(
    sc: Scenario, opts: RunOptions, why: str, refused: str | None = None
) -> dict[str, Any]:
    """summary.json rebuilt from the files a killed bench left behind (flushed as it ran).

    ``refused``: the bench refused its input before the run (the error, naming the key).
    """
    out = opts.out
    _wait_for_fsw_exit(out)
    db = load_database()
    tel = _read_numeric_csv(out / "telemetry.csv")
    t = tel.get("t_s", np.zeros(0))
    pm = pointing_metrics(t, tel.get("att_err_deg", np.zeros(0)),
                          tel.get("rate_err_deg_s", np.zeros(0)),
                          sc.expectations.settling_band_deg, sc.expectations.steady_state_window_s,
                          sc.manoeuvre_start_s)
    frames = frame_table(Icd.from_database(db))
    fr = _read_numeric_csv(out / "frames.csv")
    name_of = {m.frame_id: m.name for m in db.messages}
    sent: dict[str, int] = {}
    received: dict[str, dict[str, Any]] = {}
    for can_id, tx in zip(fr.get("id", []), fr.get("tx", []), strict=True):
        name = name_of.get(int(can_id))
        if name is None:
            continue
        if tx:
            sent[name] = sent.get(name, 0) + 1
        else:
            r = received.setdefault(name, {"received": 0, "gaps": 0, "rejected": {}})
            r["received"] += 1
    other: dict[str, dict[str, int]] = {}
    merge_counts(frames, other, "BENCH", sent, received)
    faults = []
    events = out / "events.jsonl"
    if events.exists():
        for line in events.read_text(encoding="utf-8").splitlines():
            try:
                ev = json.loads(line)
            except json.JSONDecodeError:
                continue  # a line cut by the kill
            if ev.get("event") == "fault_injected":
                faults.append(ev)
    summary: dict[str, Any] = {
        "scenario": sc.name, "scenario_file": sc.path, "mode": opts.mode, "seed": opts.seed,
        "bus": opts.bus, "sim_time_s": float(t[-1]) if len(t) else 0.0, "wall_time_s": None,
        "realtime_factor": None, "converged": pm.converged, "settling_time_s": pm.settling_time_s,
        "steady_state_attitude_error_deg": pm.steady_state_attitude_error_deg,
        "steady_state_rate_error_deg_s": pm.steady_state_rate_error_deg_s,
        "propellant_kg": float(tel["propellant_kg"][-1]) if len(t) else 0.0,
        "valve_openings": None, "frames": frames, "rejected_other": other,
        "latency_us": {"sensor_to_command": {"p50": None, "p99": None, "max": None, "n": 0}},
        "deadline_misses": None, "faults": faults, "expectations": [], "passed": False,
        "error": why, "partial": True,
    }
    if refused is not None:
        summary["refused"] = refused
    summary["fsw"] = _fsw_report(out / "fsw_stats.json", None, out)
    merge_counts(frames, other, "FSW", summary["fsw"].get("sent", {}),
                 summary["fsw"].get("received", {}))
    zero_unheard(frames, {"BENCH"} | ({"FSW"} if "received" in summary["fsw"] else set()))
    write_summary(out / "summary.json", summary)
    _plot(out, sc)
    return summary


def _read_numeric_csv(path: Path) -> dict[str, np.ndarray]:
    """Columns of a numeric CSV written as the run went; a line cut short at the end is skipped."""
    if not path.exists():
        return {}
    lines = path.read_text(encoding="utf-8").splitlines()
    if not lines:
        return {}
    head = lines[0].split(",")
    rows = []
    for line in lines[1:]:
        parts = line.split(",")
        if len(parts) != len(head):
            continue
        try:
            rows.append([float(x) for x in parts])
        except ValueError:
            continue
    data = np.array(rows, dtype=float).reshape(-1, len(head))
    return {h: data[:, i] for i, h in enumerate(head)}
