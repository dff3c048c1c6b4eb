"""Decoded export of a run's CAN trace: one channel per DBC signal, in physical units.

In: a run folder's trace (``trace.asc`` or ``trace.asc.gz``, read with python-can's
``LogReader``) and the CAN database (``dbc/thruster_hil.dbc``, cantools: scaling, offsets
and units). Out, ``thruster-hil export RUN_DIR --format ...``:

- ``mf4``: an ASAM MDF 4.10 file (asammdf, the optional extra ``[mf4]``): one channel
  group per DBC message, one channel per signal named ``MESSAGE.SIGNAL`` with the DBC's
  unit and comment, time = run time [s]. Every signal of the DBC has its channel, empty
  for a message the run never carried, so scripts see the same channels in every file.
- ``csv`` (the default): a folder with one CSV per message that occurs: ``t_s``,
  ``direction`` (``Tx``: sent by the bench; ``Rx``: received by it, i.e. sent by the
  flight software or another node), then one column per signal headed ``SIGNAL [unit]``;
  integer signals (scale 1, offset 0) as integers, the others with 15 significant digits.
  Enumerations (the DBC's value tables: modes, fault kinds) stay numeric.
- ``parquet``: a folder with one Apache Parquet file per message that occurs (pyarrow, the
  optional extra ``[parquet]``): columns ``t_s`` (float64), ``direction`` (string) and one
  per signal named as in the DBC, int64 for integer signals, float64 for the others, the
  DBC's unit in each column's field metadata (``unit``; an enumeration's value table as
  JSON in ``choices``) and the message's name and ID in
  the file's metadata: for pandas (``pandas.read_parquet``), polars, DuckDB or Spark.

A trace with no frame of the DBC is refused (a ConfigError: not a run's trace).
Every frame of the trace is decoded as it was on the wire, the bench's and the flight
software's alike (a frame the receiver rejected, e.g. for its CRC, is still exported:
the trace is what was on the bus). Error frames, remote frames, frames whose ID is not in
the DBC and frames that do not decode (length) are skipped and counted in the result.
Memory: the values are kept per signal as packed 8-byte arrays.
"""

from __future__ import annotations

import csv
import importlib.util
import json
from array import array
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can
from cantools.database.can import Database

from bench.results.record import trace_file
from dbc.errors import ConfigError

FORMATS = ("csv", "mf4", "parquet")
FLOAT64 = "d"
MDF_VERSION = "4.10"
CSV_DIGITS = ".15g"  # significant digits of a scaled value in the CSV
MF4_HINT = "an installed asammdf (pip install asammdf, or pip install -e \".[mf4]\" here)"
PARQUET_HINT = ("an installed pyarrow (pip install pyarrow, or pip install -e \".[parquet]\" "
                "here)")
NEEDS = {"mf4": ("asammdf", MF4_HINT), "parquet": ("pyarrow", PARQUET_HINT)}
"""Formats that need an optional library: its module and the hint when it is missing."""


@dataclass
class _Series:
    """One message's decoded values: times [s], directions and one array per signal."""

    t_s: array[float] = field(default_factory=lambda: array(FLOAT64))
    rx: list[bool] = field(default_factory=list)
    values: dict[str, array[float]] = field(default_factory=dict)


@dataclass
class Decoded:
    """A run's trace decoded per message, and what could not be (counts by reason)."""

    series: dict[str, _Series]
    frames: int = 0
    skipped: dict[str, int] = field(default_factory=dict)


def decode_trace(run_dir: Path, db: Database) -> Decoded:
    """Every frame of ``run_dir``'s trace decoded with ``db`` (module docstring)."""
    if not run_dir.is_dir():
        raise ConfigError("command line", "RUN_DIR", str(run_dir), "an existing run folder")
    path = trace_file(run_dir)
    if not path.exists():
        raise ConfigError(str(run_dir), "trace.asc", None, "a run folder with its CAN trace "
                          "(a campaign keeps it for failing and worst cases only: `thruster-hil "
                          "campaign rerun DIR CASE` makes the run again, trace included)")
    by_id = {m.frame_id: m for m in db.messages}
    out = Decoded({m.name: _Series(values={s.name: array(FLOAT64) for s in m.signals})
                   for m in db.messages})

    def skip(why: str) -> None:
        out.skipped[why] = out.skipped.get(why, 0) + 1

    for msg in can.LogReader(str(path)):
        if msg.is_error_frame or msg.is_remote_frame:
            skip("error or remote frame")
            continue
        spec = by_id.get(msg.arbitration_id) if not msg.is_extended_id else None
        if spec is None:
            skip("ID not in the DBC")
            continue
        try:
            decoded = spec.decode(bytes(msg.data), decode_choices=False)
        except Exception:  # cantools raises several kinds for a frame it cannot decode
            skip("does not decode")
            continue
        if not isinstance(decoded, dict):  # a container message: none in this DBC
            skip("does not decode")
            continue
        s = out.series[spec.name]
        s.t_s.append(msg.timestamp)
        s.rx.append(bool(msg.is_rx))
        for name, col in s.values.items():
            value = decoded[name]  # decode_choices=False: numbers only
            col.append(float(value) if isinstance(value, (int, float)) else float("nan"))
        out.frames += 1
    if out.frames == 0:
        skipped = ", ".join(f"{n} {why}" for why, n in sorted(out.skipped.items()))
        raise ConfigError(str(path), "<frames>", skipped or "none",
                          "a trace with frames of the CAN database (none decoded)")
    return out


def _is_integer(sig: Any) -> bool:
    """A signal whose physical values are its raw integers (scale 1, offset 0)."""
    return not sig.is_float and sig.scale == 1 and sig.offset == 0


def _text(value: float, integer: bool) -> str:
    """A value in the CSV (module docstring)."""
    return str(int(value)) if integer and value == value else format(value, CSV_DIGITS)


def _occurring(decoded: Decoded, db: Database) -> list[tuple[Any, _Series]]:
    """(message, its series) for each DBC message the trace carries, in DBC order."""
    return [(m, decoded.series[m.name]) for m in db.messages if len(decoded.series[m.name].t_s)]


def write_csv(decoded: Decoded, db: Database, folder: Path) -> list[Path]:
    """One CSV per message that occurs (module docstring); returns the paths written."""
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for m, s in _occurring(decoded, db):
        path = folder / f"{m.name}.csv"
        with open(path, "w", newline="", encoding="utf-8") as f:
            w = csv.writer(f)
            w.writerow(["t_s", "direction"] + [
                f"{sig.name} [{sig.unit}]" if sig.unit else sig.name for sig in m.signals])
            cols = [(s.values[sig.name], _is_integer(sig)) for sig in m.signals]
            for i, t in enumerate(s.t_s):
                w.writerow([format(t, CSV_DIGITS), "Rx" if s.rx[i] else "Tx",
                            *(_text(c[i], integer) for c, integer in cols)])
        written.append(path)
    return written


def write_mf4(decoded: Decoded, db: Database, path: Path) -> Path:
    """An MDF 4 file with one channel per DBC signal (module docstring)."""
    try:
        import numpy as np
        from asammdf import MDF, Signal
    except ImportError as exc:
        raise ConfigError("command line", "--format", "mf4", MF4_HINT) from exc
    mdf = MDF(version=MDF_VERSION)
    try:
        for m in db.messages:
            s = decoded.series[m.name]
            t = np.frombuffer(s.t_s, dtype=float) if len(s.t_s) else np.zeros(0)
            signals = [Signal(samples=np.frombuffer(s.values[sig.name], dtype=float)
                              if len(t) else np.zeros(0), timestamps=t,
                              name=f"{m.name}.{sig.name}", unit=sig.unit or "",
                              comment=sig.comment or "") for sig in m.signals]
            mdf.append(signals, comment=m.name)
        mdf.save(path, overwrite=True)
    finally:
        mdf.close()
    return path


def write_parquet(decoded: Decoded, db: Database, folder: Path) -> list[Path]:
    """One Parquet file per message that occurs (module docstring); the paths written."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError as exc:
        raise ConfigError("command line", "--format", "parquet", PARQUET_HINT) from exc
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for m, s in _occurring(decoded, db):
        fields = [pa.field("t_s", pa.float64(), metadata={"unit": "s"}),
                  pa.field("direction", pa.string())]
        columns: list[Any] = [pa.array(s.t_s, pa.float64()),
                              pa.array(["Rx" if rx else "Tx" for rx in s.rx], pa.string())]
        for sig in m.signals:
            kind = pa.int64() if _is_integer(sig) else pa.float64()
            meta = {"unit": sig.unit or ""}
            if sig.choices:  # an enumeration: its names, as the DBC's value table gives them
                meta["choices"] = json.dumps({int(k): str(v) for k, v in sig.choices.items()})
            fields.append(pa.field(sig.name, kind, metadata=meta))
            col = pa.array(s.values[sig.name], pa.float64())
            columns.append(col.cast(kind) if kind == pa.int64() else col)
        schema = pa.schema(fields, metadata={"message": m.name, "frame_id": hex(m.frame_id)})
        path = folder / f"{m.name}.parquet"
        pq.write_table(pa.Table.from_arrays(columns, schema=schema), path)
        written.append(path)
    return written


def add_parser(sub: Any) -> None:
    """The ``export`` subcommand of ``thruster-hil`` (its options, each checked)."""
    from dbc import options as opt

    ex = sub.add_parser("export", help="decode a run's CAN trace into one channel per DBC "
                        "signal, in physical units (MF4, CSV or Parquet)")
    ex.add_argument("run_dir", metavar="RUN_DIR", type=opt.text("RUN_DIR", "a run folder"),
                    help="a run folder (with its trace.asc or trace.asc.gz)")
    ex.add_argument("--format", type=opt.choice("--format", FORMATS), default="csv",
                    metavar="{csv,mf4,parquet}",
                    help="csv: a folder with one CSV per message, a column per signal with "
                    "its unit; mf4: one ASAM MDF 4 file, a channel MESSAGE.SIGNAL per DBC "
                    "signal (needs asammdf: pip install asammdf); parquet: a folder with one "
                    "Parquet file per message, units in the column metadata (needs pyarrow: "
                    "pip install pyarrow) (default csv)")
    ex.add_argument("--out", type=opt.text("--out", "a file or folder path"),
                    help="the MF4 file, or the CSV or Parquet folder (default: "
                    "RUN_DIR/signals.mf4, RUN_DIR/signals/ or RUN_DIR/signals_parquet/)")


def run(args: Any) -> int:
    """``thruster-hil export``: decode, write, say what was written and what was skipped."""
    from dbc.database import load_database

    run_dir = Path(args.run_dir)
    if args.format in NEEDS and importlib.util.find_spec(NEEDS[args.format][0]) is None:
        raise ConfigError("command line", "--format", args.format, NEEDS[args.format][1])
    db = load_database()
    decoded = decode_trace(run_dir, db)
    try:
        if args.format == "mf4":
            out = Path(args.out) if args.out else run_dir / "signals.mf4"
            paths = [write_mf4(decoded, db, out)]
        elif args.format == "parquet":
            out = Path(args.out) if args.out else run_dir / "signals_parquet"
            paths = write_parquet(decoded, db, out)
        else:
            out = Path(args.out) if args.out else run_dir / "signals"
            paths = write_csv(decoded, db, out)
    except OSError as exc:
        raise ConfigError("command line", "--out", str(out),
                          f"a {'file' if args.format == 'mf4' else 'folder'} this user can "
                          f"write ({exc.strerror or exc})") from exc
    n_signals = sum(len(m.signals) for m in db.messages)
    skipped = ", ".join(f"{n} {why}" for why, n in sorted(decoded.skipped.items()))
    print(f"decoded {decoded.frames} frames into {n_signals} DBC signals"
          + (f"; skipped {skipped}" if skipped else ""))
    for p in paths:
        print(f"wrote {p}")
    return 0
