"""Every bad input tried against the command lines, with the one line each must print.

One list, two users: ``test_bad_inputs.py`` runs each row (exit 2, exactly this line on
stderr, nothing else) and checks that ``docs/bad-inputs.md``'s table is :func:`table` of
this list, so the doc and the tests cannot drift. Rows run in a scratch folder made by
:func:`make_files` (relative paths below are inside it; ``scenarios`` is the repository's).
``python -m tests.bench.operator.bad_inputs`` prints the table for the doc.
"""

from __future__ import annotations

import json
import shlex
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[3]
QUICKSTART = "scenarios/quickstart.toml"
DEEP = 100_000  # nesting of the deep files: what the issue reported as a RecursionError
HUGE_ARRAY = 5_000_000  # elements of huge.toml: a 10 MB file
LONG_SET = 20_000  # elements of a --set value: 40 kB, inside one argument's limit
SHELL_DEPTH = 40  # nesting of a --set value
MANY_DIGITS = 5_000  # digits of an integer: more than Python converts to int by default
FSW = "python -m flight_sw"
HIL = "thruster-hil"


@dataclass(frozen=True)
class Row:
    """One bad input: the tool, its arguments (as run, and as the doc shows them), the line."""

    tool: str  # HIL or FSW
    args: tuple[str, ...]
    message: str
    shown: str = ""  # the arguments as the doc shows them (default: shell-quoted args)

    @property
    def input_text(self) -> str:
        """The arguments as the doc's table shows them."""
        return self.shown or shlex.join(self.args)


def _r(tool: str, args: str, message: str, shown: str = "") -> Row:
    return Row(tool, tuple(shlex.split(args)), message, shown)


def _run(extra: str, message: str, shown: str = "") -> Row:
    return _r(HIL, f"run {QUICKSTART} {extra}", message, shown)


LONG_SET_ARG = "vehicle.mass_kg=[" + ", ".join(["0"] * LONG_SET) + "]"
DEEP_SET_ARG = "a=" + "[" * SHELL_DEPTH + "]" * SHELL_DEPTH

ROWS: list[Row] = [
    # thruster-hil run: options
    _run("--duration inf", "thruster-hil: error: command line: --duration = 'inf': expected a "
         "finite number in [0.02, 1e+06] [s]"),
    _run("--duration nan", "thruster-hil: error: command line: --duration = 'nan': expected a "
         "finite number in [0.02, 1e+06] [s]"),
    _run("--duration 1e300", "thruster-hil: error: command line: --duration = '1e300': expected "
         "a finite number in [0.02, 1e+06] [s]"),
    _run("--duration 1e7", "thruster-hil: error: command line: --duration = '1e7': expected a "
         "finite number in [0.02, 1e+06] [s]"),
    _run("--duration 0.001", "thruster-hil: error: command line: --duration = '0.001': expected "
         "a finite number in [0.02, 1e+06] [s]"),
    _run("--duration -1", "thruster-hil: error: command line: --duration = '-1': expected a "
         "finite number in [0.02, 1e+06] [s]"),
    _run("--duration ten", "thruster-hil: error: command line: --duration = 'ten': expected a "
         "finite number in [0.02, 1e+06] [s]"),
    _run("--seed -1", "thruster-hil: error: command line: --seed = '-1': expected an integer in "
         "[0, 9223372036854775807]"),
    _run("--seed 1.5", "thruster-hil: error: command line: --seed = '1.5': expected an integer "
         "in [0, 9223372036854775807]"),
    _run("--seed 9223372036854775808", "thruster-hil: error: command line: --seed = "
         "'9223372036854775808': expected an integer in [0, 9223372036854775807]"),
    _run("--mode fast", "thruster-hil: error: command line: --mode = 'fast': expected one of "
         "lockstep, realtime"),
    _run("--bus virtual:x", "thruster-hil: error: command line: --bus = 'virtual:x': expected an "
         "interface that other processes share (a virtual bus exists inside one process: the "
         "bench, the flight software and the tools are separate processes and would never "
         "hear each other; use hilbus:NAME or socketcan:IFACE)"),
    _run("--bus nosuch:foo", "thruster-hil: error: command line: --bus = 'nosuch:foo': expected "
         "a python-can interface: one of canalystii, cantact, etas, gs_usb, hilbus, iscan, "
         "ixxat, kvaser, neousys, neovi, nican, nixnet, pcan, robotell, seeedstudio, serial, "
         "slcan, socketcan, socketcand, systec, udp_multicast, usb2can, vector"),
    _run("--bus hilbus", "thruster-hil: error: command line: --bus = 'hilbus': expected "
         "INTERFACE:CHANNEL[?key=value&...], e.g. socketcan:vcan0 or hilbus:default"),
    _run("--out ''", "thruster-hil: error: command line: --out = '': expected a folder path"),
    _run("--junit scenarios", "thruster-hil: error: command line: --junit = 'scenarios': "
         "expected a file path, not a folder"),
    _run("--junit ''", "thruster-hil: error: command line: --junit = '': expected a file path"),
    _run("--set 'expectations.settling_time_s_max={max=5.0, req=\"has space\"}'",
         "thruster-hil: error: command line --set expectations.settling_time_s_max={max=5.0, "
         "req=\"has space\"} (on scenarios/quickstart.toml): "
         "expectations.settling_time_s_max.req = 'has space': expected a requirement ID: 1 "
         "to 64 letters, digits or . _ : / -, starting with a letter or digit (e.g. "
         "\"GNC-ATT-012\")"),
    _run("--fsw-cmd ''", "thruster-hil: error: command line: --fsw-cmd = '': expected a "
         "command line"),
    _run("--nosuch", "thruster-hil: error: unrecognized arguments: --nosuch"),
    _r(HIL, "run", "thruster-hil: error: the following arguments are required: scenario"),
    # thruster-hil run: the scenario file
    _r(HIL, "run missing.toml", "thruster-hil: error: missing.toml: <file> = 'missing.toml': "
       "expected a readable scenario file (No such file or directory)"),
    _r(HIL, "run /dev/zero", "thruster-hil: error: /dev/zero: <file> = '/dev/zero': expected a "
       "scenario file of at most 1048576 bytes (this one is larger)"),
    _r(HIL, "run huge.toml", "thruster-hil: error: huge.toml: <file> = 'huge.toml': expected a "
       "scenario file of at most 1048576 bytes (this one is larger)",
       shown="run huge.toml  # a = [0, 0, ...]: 5 000 000 elements, 10 MB"),
    _r(HIL, "run binary.toml", "thruster-hil: error: binary.toml: <file> = 'binary.toml': "
       "expected a UTF-8 text file (byte 6 is not UTF-8)",
       shown="run binary.toml  # a = 1, then bytes ff fe"),
    _r(HIL, "run deep.toml", "thruster-hil: error: deep.toml: <nesting> = 'more than 32 "
       "levels': expected tables, arrays and dotted keys nested at most 32 deep",
       shown="run deep.toml  # a = [[[...]]]: 100 000 nested arrays"),
    _r(HIL, "run deep_tables.toml", "thruster-hil: error: deep_tables.toml: <nesting> = 'more "
       "than 32 levels': expected tables, arrays and dotted keys nested at most 32 deep",
       shown="run deep_tables.toml  # [a.a.a...]: 100 000 nested tables"),
    _r(HIL, "run bigint.toml", "thruster-hil: error: bigint.toml: <syntax> = 'an integer of "
       "more than 4300 digits': expected valid TOML with integers of at most 4300 digits",
       shown="run bigint.toml  # seed = 1000...0: 5 000 digits"),
    # thruster-hil run: --set overrides
    _run("--set scenario.duration_s=inf", "thruster-hil: error: command line --set "
         "scenario.duration_s=inf (on scenarios/quickstart.toml): scenario.duration_s = inf: "
         "expected a finite number in [0.02, 1e+06]"),
    _run("--set scenario.duration_s=1e7", "thruster-hil: error: command line --set "
         "scenario.duration_s=1e7 (on scenarios/quickstart.toml): scenario.duration_s = "
         "10000000.0: expected a finite number in [0.02, 1e+06]"),
    _run("--set scenario.seed=-1", "thruster-hil: error: command line --set scenario.seed=-1 "
         "(on scenarios/quickstart.toml): scenario.seed = -1: expected an integer in [0, "
         "9223372036854775807]"),
    _run("--set bus.bitrate_bps=2000000", "thruster-hil: error: command line --set "
         "bus.bitrate_bps=2000000 (on scenarios/quickstart.toml): bus.bitrate_bps = 2000000: "
         "expected an integer in [125000, 1000000]"),
    _run("--set bus.bitrate_bps=1e6", "thruster-hil: error: command line --set "
         "bus.bitrate_bps=1e6 (on scenarios/quickstart.toml): bus.bitrate_bps = 1000000.0: "
         "expected an integer in [125000, 1000000]"),
    _run("--set vehicle.mass_kg=-1", "thruster-hil: error: command line --set "
         "vehicle.mass_kg=-1 (on scenarios/quickstart.toml): vehicle.mass_kg = -1: expected a "
         "finite number > 0"),
    _run("--set vehicle.mass_kg=nan", "thruster-hil: error: command line --set "
         "vehicle.mass_kg=nan (on scenarios/quickstart.toml): vehicle.mass_kg = nan: expected "
         "a finite number > 0"),
    _run("--set nosuch=1", "thruster-hil: error: command line --set nosuch=1 (on "
         "scenarios/quickstart.toml): nosuch = 1: expected no such key here (this table "
         "takes: bus, disturbance, dynamics, environment, events, expectations, faults, "
         "flight_sw, initial, manoeuvre, scenario, sensors, thrusters, vehicle)"),
    _run("--set vehicle.mass_kg", "thruster-hil: error: command line (--set on "
         "scenarios/quickstart.toml): --set = 'vehicle.mass_kg': expected KEY=VALUE with a "
         "dotted KEY"),
    Row(HIL, ("run", QUICKSTART, "--set", LONG_SET_ARG),
        "thruster-hil: error: command line --set vehicle.mass_kg=[0, 0, 0, 0, 0, 0, 0, 0, 0, 0, "
        "0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, ... (on "
        "scenarios/quickstart.toml): vehicle.mass_kg = list of 20000 items: [0, 0, 0, 0, 0, "
        "0, ...]: expected a finite number > 0",
        shown=f"run {QUICKSTART} --set 'vehicle.mass_kg=[0, 0, ...]'  # 20 000 zeros"),
    Row(HIL, ("run", QUICKSTART, "--set", DEEP_SET_ARG),
        "thruster-hil: error: command line (--set on scenarios/quickstart.toml): --set = "
        "str of 82 chars: "
        "'a=[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[...]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]': "
        "expected tables, arrays and dotted keys nested at most 32 deep",
        shown=f"run {QUICKSTART} --set 'a=[[[...]]]'  # 40 nested arrays"),
    _run("--set bus.bitrate_bps=1" + "0" * MANY_DIGITS, "thruster-hil: error: command line "
         "--set bus.bitrate_bps=10000000000000000000000000000000000000000000000000000000000000"
         "00... (on scenarios/quickstart.toml): bus.bitrate_bps = str of 5001 chars: "
         "'1000000000000000000000000000000000000...00000000000000000000000000000000000000': "
         "expected an integer in [125000, 1000000]",
         shown=f"run {QUICKSTART} --set bus.bitrate_bps=1000...0  # 5 000 digits"),
    # thruster-hil bench
    _r(HIL, f"bench {QUICKSTART} --bus virtual:x", "thruster-hil: error: command line: --bus = "
       "'virtual:x': expected an interface that other processes share (a virtual bus exists "
       "inside one process: the bench, the flight software and the tools are separate "
       "processes and would never hear each other; use hilbus:NAME or socketcan:IFACE)"),
    _r(HIL, f"bench {QUICKSTART} --duration inf", "thruster-hil: error: command line: "
       "--duration = 'inf': expected a finite number in [0.02, 1e+06] [s]"),
    _r(HIL, f"bench {QUICKSTART} --fsw-cmd x", "thruster-hil: error: unrecognized arguments: "
       "--fsw-cmd x"),
    # thruster-hil report
    _r(HIL, "report missing", "thruster-hil: error: missing: summary.json = None: expected a "
       "run folder (no summary.json)"),
    _r(HIL, "report notjson", "thruster-hil: error: notjson/summary.json: <syntax> = 'Expecting "
       "value: line 1 column 1 (char 0)': expected valid JSON",
       shown="report notjson  # its summary.json: not JSON"),
    _r(HIL, "report empty", "thruster-hil: error: empty/summary.json: latency_us = None: "
       "expected a summary.json written by thruster-hil (this key is missing)",
       shown="report empty  # its summary.json: {}"),
    _r(HIL, "report ''", "thruster-hil: error: command line: RUN_DIR = '': expected a run "
       "folder"),
    # thruster-hil export
    _r(HIL, "export missing", "thruster-hil: error: command line: RUN_DIR = 'missing': "
       "expected an existing run folder"),
    _r(HIL, "export missing --format xls", "thruster-hil: error: command line: --format = "
       "'xls': expected one of csv, mf4, parquet"),
    # thruster-hil monitor
    _r(HIL, "monitor --bus hilbus:bad-input-monitor", "thruster-hil: error: command line: "
       "--duration = None: expected a duration when the output is not a terminal (the "
       "monitor then prints its last picture)",
       shown="monitor --bus hilbus:bad-input-monitor  # output not a terminal"),
    _r(HIL, "monitor --bus hilbus --duration 1", "thruster-hil: error: command line: --bus = "
       "'hilbus': expected INTERFACE:CHANNEL[?key=value&...], e.g. socketcan:vcan0 or "
       "hilbus:default"),
    # thruster-hil replay
    _r(HIL, "replay missing", "thruster-hil: error: command line: RUN_DIR = 'missing': "
       "expected an existing run folder"),
    _r(HIL, "replay scenarios --external", "thruster-hil: error: command line: --bus = None: "
       "expected the bus of the flight software already running (--external)"),
    # thruster-hil timing
    _r(HIL, "timing", "thruster-hil: error: timing: RUN_DIR/--live = None: expected a run "
       "folder or --live"),
    _r(HIL, "timing missing", "thruster-hil: error: missing: summary.json = None: expected a "
       "run folder (no summary.json)"),
    _r(HIL, "timing runs/a --live", "thruster-hil: error: timing: RUN_DIR/--live = 'runs/a': "
       "expected a run folder or --live"),
    _r(HIL, "timing runs/a --duration 5", "thruster-hil: error: command line: --duration = "
       "5.0: expected absent without --live (a run folder has its own bus and duration)"),
    _r(HIL, "timing runs/a --window-ms 0", "thruster-hil: error: command line: --window-ms = "
       "'0': expected a finite number in [0.01, 3.6e+06] [ms]"),
    _r(HIL, "timing runs/a --window-ms nan", "thruster-hil: error: command line: --window-ms = "
       "'nan': expected a finite number in [0.01, 3.6e+06] [ms]"),
    _r(HIL, "timing runs/a --abs-tol-ms inf", "thruster-hil: error: command line: --abs-tol-ms "
       "= 'inf': expected a finite number <= 1e+06 [ms]"),
    _r(HIL, "timing runs/a --rel-tol-pct 100", "thruster-hil: error: command line: "
       "--rel-tol-pct = '100': expected a finite number < 100 [%]"),
    _r(HIL, "timing --live --bus virtual:x", "thruster-hil: error: command line: --bus = "
       "'virtual:x': expected an interface that other processes share (a virtual bus exists "
       "inside one process: the bench, the flight software and the tools are separate "
       "processes and would never hear each other; use hilbus:NAME or socketcan:IFACE)"),
    _r(HIL, "timing --live --duration inf", "thruster-hil: error: command line: --duration = "
       "'inf': expected a finite number in (0, 1e+06] [s]"),
    _r(HIL, "timing --live --duration 0", "thruster-hil: error: command line: --duration = "
       "'0': expected a finite number in (0, 1e+06] [s]"),
    _r(HIL, "timing --live --first-frame-timeout -1", "thruster-hil: error: command line: "
       "--first-frame-timeout = '-1': expected a finite number in (0, 1e+06] [s]"),
    _r(HIL, "timing --live --bitrate 0", "thruster-hil: error: command line: --bitrate = '0': "
       "expected an integer in [5000, 1000000]"),
    _r(HIL, "timing --live --bitrate 1e6", "thruster-hil: error: command line: --bitrate = "
       "'1e6': expected an integer in [5000, 1000000]"),
    # thruster-hil inject
    _r(HIL, "inject stuck_open --target 3 --duration inf", "thruster-hil: error: command line: "
       "--duration = 'inf': expected a finite number"),
    _r(HIL, "inject stuck_open --target 3 --param nan", "thruster-hil: error: command line: "
       "--param = 'nan': expected a finite number"),
    _r(HIL, "inject stuck_open --target 3 --duration -1", "thruster-hil: error: thruster-hil "
       "inject: --duration = -1.0: expected 0..655.35 (FAULT_CMD.Duration in the DBC)"),
    _r(HIL, "inject stuck_open --target 99999", "thruster-hil: error: thruster-hil inject: "
       "--target = 99999: expected 0..2047 (FAULT_CMD.Target in the DBC)"),
    _r(HIL, "inject stuck_open --target x", "thruster-hil: error: command line: --target = 'x': "
       "expected an integer"),
    _r(HIL, "inject stuck_open", "thruster-hil: error: the following arguments are required: "
       "--target"),
    _r(HIL, "inject nosuch --target 3", "thruster-hil: error: thruster-hil inject: kind = "
       "'nosuch': expected one of stuck_closed, stuck_open, degraded, misaligned, delayed, "
       "intermittent, leak, drop, delay, corrupt, duplicate, babbling, bus_off, link_error, "
       "bias_jump, frozen, outage, noise"),
    _r(HIL, "inject stuck_open --target 3 --print-frame 99", "thruster-hil: error: thruster-hil "
       "inject: --print-frame = 99: expected an alive counter 0..14"),
    _r(HIL, "inject stuck_open --target 3 --print-frame 0 --bus hilbus:x", "thruster-hil: "
       "error: command line: --bus = 'hilbus:x': expected absent with --print-frame (the "
       "frame is printed, not sent)"),
    _r(HIL, "inject stuck_open --target 3 --bus virtual:x", "thruster-hil: error: command line: "
       "--bus = 'virtual:x': expected an interface that other processes share (a virtual bus "
       "exists inside one process: the bench, the flight software and the tools are separate "
       "processes and would never hear each other; use hilbus:NAME or socketcan:IFACE)"),
    # thruster-hil campaign
    _r(HIL, f"campaign {QUICKSTART} --out c --jobs 0", "thruster-hil: error: command line: "
       "--jobs = '0': expected an integer in [1, 64]"),
    _r(HIL, f"campaign {QUICKSTART} --out c --jobs 1000", "thruster-hil: error: command line: "
       "--jobs = '1000': expected an integer in [1, 64]"),
    _r(HIL, f"campaign {QUICKSTART} --out c --fault-time nan", "thruster-hil: error: command "
       "line: --fault-time = 'nan': expected a finite number >= 0 [s]"),
    _r(HIL, f"campaign {QUICKSTART} --out c --fault-time 60", "thruster-hil campaign: error: "
       "command line: --fault-time = 60.0: expected a time in [0, 60) s (the scenario's duration)"),
    _r(HIL, f"campaign {QUICKSTART} --out c --kinds leak", "thruster-hil: error: command line: "
       "--kinds = 'leak': expected one of stuck_closed, stuck_open"),
    _r(HIL, f"campaign {QUICKSTART}", "thruster-hil: error: the following arguments are "
       "required: --out"),
    # thruster-hil campaign with a campaign file, rerun, margin
    _r(HIL, "campaign bad_alias.toml --out c",
       "thruster-hil campaign: error: bad_alias.toml: dispersions[0].name = 'mas': expec"
       "ted one of accel_bias, bitrate, close_delay, com_offset, fault_target, fault_tim"
       "e, gyro_bias, gyro_noise, inertia_xx, inertia_yy, inertia_zz, initial_attitude, "
       "initial_position, initial_rate, initial_velocity, isp, latency, mass, min_on_tim"
       "e, misalignment, open_delay, star_tracker_noise, thrust_scale (did you mean 'mas"
       "s'?)"),
    _r(HIL, "campaign impossible.toml --out c",
       "thruster-hil campaign: error: impossible.toml: case 0000: vehicle.inertia_B_kgm2"
       " = [[159.5, 0.0, 0.0], [0.0, 72.19, 0.0], [0.0, 0.0, 72.19]]: expected principal"
       " moments obeying the triangle inequality (a physical body) (a value a dispersion"
       " gave this case: check its distribution)"),
    _r(HIL, "campaign impossible.toml --out c --kinds stuck_open",
       "thruster-hil campaign: error: command line: --kinds = ['stuck_open']: expected a"
       "bsent with a campaign file (its [campaign] table says fault_time_s and failures)"),
    _r(HIL, "campaign rerun nowhere 0001",
       "thruster-hil campaign: error: command line: CASE = '0001': expected a case of th"
       "e campaign folder nowhere (cannot read nowhere/cases/0001/case.json and result.j"
       "son: No such file or directory)"),
    _r(HIL, f"campaign margin {QUICKSTART} --key vehicle.mas_kg --toward 1 --out m",
       "thruster-hil campaign: error: command line: --key = 'vehicle.mas_kg': expected a"
       " key the scenario has (vehicle.mas_kg: not in the scenario)"),
    _r(HIL, f"campaign margin {QUICKSTART} --key latency --toward 0.001 --out m",
       "thruster-hil campaign: error: command line: --toward = 0.001: expected a value o"
       "ther than the nominal 0.001"),
    # the flight software's own entry point
    _r(FSW, "--config missing.json", "flight_sw: error: missing.json: <file> = 'missing.json': "
       "expected a readable configuration file (No such file or directory)"),
    _r(FSW, "--config /dev/zero", "flight_sw: error: /dev/zero: <file> = '/dev/zero': expected "
       "a configuration file of at most 1048576 bytes (this one is larger)"),
    _r(FSW, "--config deep.json", "flight_sw: error: deep.json: <nesting> = 'more than 32 "
       "levels': expected tables, arrays and dotted keys nested at most 32 deep",
       shown="--config deep.json  # [[[...]]]: 100 000 nested arrays"),
    _r(FSW, "--config notjson/summary.json", "flight_sw: error: notjson/summary.json: <syntax> "
       "= 'Expecting value: line 1 column 1 (char 0)': expected valid JSON"),
    _r(FSW, "--config fsw.json --bus virtual:x", "flight_sw: error: command line: --bus = "
       "'virtual:x': expected an interface that other processes share (a virtual bus exists "
       "inside one process: the bench, the flight software and the tools are separate "
       "processes and would never hear each other; use hilbus:NAME or socketcan:IFACE)"),
    _r(FSW, "--config fsw.json --mode fast", "flight_sw: error: command line: --mode = 'fast': "
       "expected one of lockstep, realtime"),
    _r(FSW, "--config fsw.json --stats missing/stats.json", "flight_sw: error: command line: "
       "--stats = 'missing/stats.json': expected a file path in an existing folder this user "
       "can write"),
    _r(FSW, "--config big_window.json --check", "flight_sw: error: fdir_16thr.toml: "
       "flight_sw.thruster_fdir.valve_status.window_samples = 1000000000000: expected an "
       "integer in [1, 10000000]",
       shown="--config big_window.json --check  # window_samples = 1000000000000"),
    _r(FSW, "", "flight_sw: error: the following arguments are required: --config"),
]


def _cell(text: str) -> str:
    """A table cell: code, with the table's separator escaped."""
    return "`" + text.replace("|", "\\|") + "`" if text else ""


def table(rows: list[Row] = ROWS) -> str:
    """The doc's markdown table of ``rows``: tool and arguments, then the line printed."""
    lines = ["| command | arguments | what it prints (stderr; exit code 2) |",
             "| --- | --- | --- |"]
    for r in rows:
        cells = (r.tool, r.input_text, r.message)
        lines.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    return "\n".join(lines) + "\n"


def make_files(folder: Path) -> None:
    """The files the rows name, in ``folder`` (the rows' working directory)."""
    (folder / "scenarios").symlink_to(REPO / "scenarios")
    (folder / "huge.toml").write_text("a = [" + "0," * HUGE_ARRAY + "]\n")
    (folder / "binary.toml").write_bytes(b"a = 1\n\xff\xfe")
    (folder / "deep.toml").write_text("a = " + "[" * DEEP + "]" * DEEP + "\n")
    (folder / "deep_tables.toml").write_text("[" + "a." * DEEP + "a]\n")
    (folder / "bigint.toml").write_text("[scenario]\nseed = 1" + "0" * MANY_DIGITS + "\n")
    (folder / "deep.json").write_text("[" * DEEP + "]" * DEEP)
    for name, text in (("notjson", "not json"), ("empty", "{}")):
        (folder / name).mkdir()
        (folder / name / "summary.json").write_text(text)
    head = '[campaign]\nscenario = "scenarios/quickstart.toml"\n[[dispersions]]\n'
    (folder / "bad_alias.toml").write_text(head + 'name = "mas"\ndist = "sweep"\nvalues = [1]\n')
    (folder / "impossible.toml").write_text(head + 'name = "inertia_xx"\ndist = "sweep"\n'
                                            'values = [10.0]\napply = "scale"\n')
    from bench.scenario.load import load_scenario

    config = load_scenario(REPO / "scenarios" / "fdir_16thr.toml").fsw_config()
    config["source"] = "fdir_16thr.toml"  # where its values came from, as errors name it
    (folder / "fsw.json").write_text(json.dumps(config))
    config["flight_sw"]["thruster_fdir"]["valve_status"]["window_samples"] = 10**12
    (folder / "big_window.json").write_text(json.dumps(config))


if __name__ == "__main__":
    print(table(), end="")
