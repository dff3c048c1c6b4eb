"""How much a run records, and the run folder's per-frame and telemetry files as text.

Three levels (``thruster-hil run --record``, ``bench --record``):

* ``standard`` (the default): the CAN trace and the CSV tables (``trace.asc``,
  ``frames.csv``, ``telemetry.csv``, ``chains.csv``, ``valve_pulses.csv``) are written
  gzip-compressed, as ``trace.asc.gz``, ``frames.csv.gz``, ... : the same rows, about a
  fifth of the size (figures below). python-can reads ``.asc.gz``
  as it is (``can.LogReader``, ``python -m can.player``); for a tool that wants plain ASC
  (CANoe, SavvyCAN), ``gunzip trace.asc.gz``.
* ``full``: the same files uncompressed.
* ``lean`` (a campaign's cases, bench.campaign): ``telemetry.csv.gz`` at a tenth of the
  rate (every :data:`LEAN_TELEMETRY_EVERY`-th instant) and the trace as ``trace.blf`` only:
  no ``trace.asc``, ``frames.csv``, ``chains.csv`` or ``valve_pulses.csv``. The summary is
  the same (its figures are streamed, never read back from the files); a case's whole
  folder comes from running it again (``thruster-hil campaign rerun``: lockstep is exact).
  About a third less of the bench's CPU time goes into the files (docs/campaigns.md).

Every level writes the trace in Vector's binary logging format, ``trace.blf``
(bench.wire.trace; itself zlib-compressed, ~5 kB per simulated second), the same bytes at
every level, so CANoe and CANalyzer open any run's trace as it is.

Sizes (``python benchmarks/run_resources.py --durations 600``, quickstart): about 19 kB per
simulated second at ``standard`` (``trace.blf``'s 5 kB included), 79 kB at ``full`` (README,
"What a run gives you").

Compressed files are flushed as the run goes like the plain ones (a gzip *sync flush*:
everything written so far can be decompressed), so a crashed or killed run's files are
readable up to the last flush; :func:`read_lines` reads such a file without its trailer,
and :func:`seal` (run by the supervisor when the bench was killed) rewrites it as a whole
gzip file, so ``gunzip``, ``zcat`` and ``can.LogReader`` read it to the end without error.
The gzip header carries no time (``mtime=0``) and no name, so the same rows give the same
bytes.

Readers find a file by its plain name (:func:`run_file`), whichever level wrote it.
"""

from __future__ import annotations

import gzip
import io
import os
import zlib
from collections.abc import Iterator
from pathlib import Path
from typing import IO, TextIO

from dbc.errors import ConfigError

RECORD_STANDARD = "standard"
RECORD_FULL = "full"
RECORD_LEAN = "lean"
RECORD_CHOICES = (RECORD_STANDARD, RECORD_FULL, RECORD_LEAN)
LEAN_TELEMETRY_EVERY = 10
"""At ``lean``, telemetry.csv keeps one instant in this many (10 Hz of the 100 Hz)."""
GZ_SUFFIX = ".gz"
# zlib level: 6 (zlib's default) makes the files ~4.5x smaller than plain text, level 1
# ~3.7x; the compression runs while the flight software computes its cycle (deferred
# writing), so the better ratio costs no real-time factor.
GZIP_LEVEL = 6
# The run loops flush the run-folder files this often (simulated time): a killed bench loses
# at most this much of them. Each gzip sync flush ends a deflate block; flushing every
# 0.1 s made the compressed files ~0.8 kB per simulated second bigger than every 0.5 s
# (quickstart).
FLUSH_PERIOD_NS = 500_000_000


def check_record(record: str, where: str = "--record") -> str:
    """``record`` if it is a level of :data:`RECORD_CHOICES`; else ConfigError naming it."""
    if record not in RECORD_CHOICES:
        raise ConfigError(where, "record", record, " or ".join(RECORD_CHOICES))
    return record


def file_name(base: str, record: str) -> str:
    """The name of the run-folder file ``base`` (e.g. ``telemetry.csv``) at level ``record``."""
    return base if check_record(record) == RECORD_FULL else base + GZ_SUFFIX


def writes_tables(record: str) -> bool:
    """Whether level ``record`` writes trace.asc and the per-frame, chain and pulse tables
    (every level but ``lean``)."""
    return check_record(record) != RECORD_LEAN


def run_file(run_dir: Path, base: str) -> Path:
    """The file ``base`` of a run folder as written: ``base``, else ``base.gz`` if that one
    exists (a standard record), else ``base`` (missing)."""
    plain = run_dir / base
    if plain.exists():
        return plain
    packed = run_dir / (base + GZ_SUFFIX)
    return packed if packed.exists() else plain


def open_writer(path: Path) -> TextIO:
    """A text file to write at ``path``: gzip-compressed (level :data:`GZIP_LEVEL`, no time in
    the header) when the name ends in ``.gz``. Its ``flush`` reaches the disk's page cache
    with everything written so far decodable (a gzip sync flush)."""
    if path.suffix != GZ_SUFFIX:
        return open(path, "w", newline="", encoding="utf-8")
    raw = open(path, "wb")  # noqa: SIM115 - owned by the GzipFile's wrapper
    return _OwningText(_gzip_writer(raw), raw)


def _gzip_writer(raw: IO[bytes]) -> gzip.GzipFile:
    """A gzip stream onto ``raw``: level :data:`GZIP_LEVEL`, no name or time in its header
    (the same bytes give the same file)."""
    return gzip.GzipFile(filename="", mode="wb", compresslevel=GZIP_LEVEL, fileobj=raw, mtime=0)


class _OwningText(io.TextIOWrapper):
    """A UTF-8 text stream over a GzipFile that also flushes and closes the file beneath."""

    def __init__(self, packed: gzip.GzipFile, raw: IO[bytes]) -> None:
        super().__init__(packed, encoding="utf-8", newline="", write_through=True)
        self._raw = raw

    def flush(self) -> None:
        super().flush()  # the text layer, then the GzipFile (a sync flush)
        self._raw.flush()

    def close(self) -> None:
        if not self.closed:
            super().close()  # writes the gzip trailer
            self._raw.close()


def trace_file(run_dir: Path) -> Path:
    """The run's CAN trace to read: ``trace.asc`` as written (plain or ``.gz``), else
    ``trace.blf`` (a lean record's only trace; python-can reads both), else the missing
    ``trace.asc``."""
    asc = run_file(run_dir, "trace.asc")
    if asc.exists():
        return asc
    blf = run_dir / "trace.blf"
    return blf if blf.exists() else asc


def read_lines(path: Path) -> Iterator[str]:
    """The lines of a run-folder text file, plain or ``.gz``, read lazily, each ending in
    ``\n`` (universal newlines: the CSV writer ends rows with ``\r\n``). A compressed file
    whose writer died (no gzip trailer, a block cut short) yields every line up to its last
    flush (a line cut short at the end may be left out; a plain file gives it without its
    newline: readers skip it either way)."""
    if path.suffix != GZ_SUFFIX:
        with open(path, encoding="utf-8") as f:
            yield from f
        return
    with gzip.open(path, "rt", encoding="utf-8") as f:
        try:
            yield from f
        except (EOFError, zlib.error, gzip.BadGzipFile):
            return  # the end of what was flushed before the writer stopped



SEAL_CHUNK_BYTES = 1 << 20  # read and decompress a file this much at a time
GZIP_WBITS = 16 + zlib.MAX_WBITS  # zlib: a gzip stream (header and trailer)


def _flushed_bytes(path: Path) -> Iterator[bytes]:
    """The decompressed bytes of a gzip file up to where it ends or breaks off, in chunks
    (a file whose writer died ends after its last sync flush)."""
    unpack = zlib.decompressobj(GZIP_WBITS)
    with open(path, "rb") as f:
        while chunk := f.read(SEAL_CHUNK_BYTES):
            try:
                out = unpack.decompress(chunk)
            except zlib.error:
                return  # a block cut short in the middle (a full disk)
            if out:
                yield out
            if unpack.eof:
                return


def is_whole(path: Path) -> bool:
    """True if the gzip file ``path`` decompresses to its end, trailer included."""
    try:
        with gzip.open(path, "rb") as f:
            while f.read(SEAL_CHUNK_BYTES):
                pass
    except (EOFError, zlib.error, gzip.BadGzipFile):
        return False
    return True


def seal(path: Path) -> bool:
    """Make a ``.gz`` run file whose writer died (no trailer, or cut short) a whole gzip
    file holding the same bytes up to the writer's last flush, so ``gunzip``, ``zcat`` and
    ``can.LogReader`` read it to the end without error. Written beside it and renamed over
    it (a failure leaves the original). Returns True if rewritten; a whole, plain or
    missing file is left as it is (False)."""
    if path.suffix != GZ_SUFFIX or not path.exists() or is_whole(path):
        return False
    tmp = path.with_name(".sealing-" + path.name)
    with open(tmp, "wb") as raw, _gzip_writer(raw) as packed:
        for chunk in _flushed_bytes(path):
            packed.write(chunk)
    os.replace(tmp, path)
    return True
