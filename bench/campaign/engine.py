"""Run a campaign's cases on Dask: a local cluster sized to the machine, or a scheduler.

One Dask task is one case (:func:`bench.campaign.case_run.run_case`: one ``thruster-hil
run`` process, its bench + flight-software pair on a channel of its own), started warm by
the worker's zygote (bench.campaign.warm_workers: a worker plugin, taken off the workers
when the campaign ends). With no
scheduler, a ``distributed.LocalCluster`` of one single-threaded worker process per CPU
(``available_cpus``) is started and closed with the campaign; ``scheduler`` =
``tcp://HOST:PORT`` sends the cases to a cluster started with Dask's own commands
(``dask scheduler``, ``dask worker``), whose workers have the project installed and see
``out`` at the same path.

- A case that raises (a crash, a timeout) is submitted again once, and ``notice`` says
  so (the console); a case whose worker dies is rescheduled by Dask; after that it is
  recorded as an error row (``attempts``: how many ran), never dropped. A case whose
  configuration the run refused (exit 2) is not retried: its row says ``refused``.
- Resume: a case whose ``cases/NAME/result.json`` exists with the same case is not run
  again; stale attempt folders (a lost worker's, an interrupted campaign's) are removed
  before and after.
- Results do not depend on the executor, the number of workers or the order cases finish
  in: each row comes from its own case alone, and rows are returned in case order.

``progress(done, total, row)`` is called as each case ends (and for each resumed case).
"""

from __future__ import annotations

import contextlib
import json
import logging
import shutil
import signal
import socket
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from bench.campaign.case_run import (
    ATTEMPT_MARK,
    CASE_FILE,
    RESULT_FILE,
    STATUS_OK,
    error_row,
    run_case,
)
from bench.results.record import RECORD_STANDARD
from dbc.errors import ConfigError
from transport.lockstep import LOCKSTEP_SPIN_ENV, available_cpus

PROCESSES_PER_CASE = 2  # bench + flight software
SCHEDULER_TIMEOUT_S = 30.0  # connecting to --scheduler
SCHEDULER_PROBE_S = 5.0  # the first TCP connection to --scheduler (check_scheduler)
TCP_SCHEME = "tcp://"
RETRIES = 1
DASK_LOG_LEVEL = logging.CRITICAL
"""Dask's own log lines (a failed task's traceback at ERROR) would bury the progress; the
engine says itself what failed and what is retried."""
Progress = Callable[[int, int, dict[str, Any]], None]


def done_rows(cases_dir: Path, cases: list[dict[str, Any]]) -> dict[int, dict[str, Any]]:
    """Rows of cases already complete in ``cases_dir`` (same case), by index."""
    out = {}
    for c in cases:
        d = cases_dir / c["name"]
        try:
            same = json.loads((d / CASE_FILE).read_text(encoding="utf-8")) == c
            row = json.loads((d / RESULT_FILE).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if same and row.get("status") == STATUS_OK:
            out[c["index"]] = row
    return out


def _clear_attempts(cases_dir: Path) -> None:
    if cases_dir.exists():
        for d in cases_dir.iterdir():
            if ATTEMPT_MARK in d.name:
                shutil.rmtree(d, ignore_errors=True)


@contextlib.contextmanager
def _sigint_ignored() -> Iterator[None]:
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _unregister(client: Any, name: str) -> None:
    """Take the campaign's zygotes off the workers (they end with it)."""
    with contextlib.suppress(Exception):  # a cluster already gone has none left
        client.unregister_worker_plugin(name)


def check_scheduler(scheduler: str) -> None:
    """ConfigError at once if a ``tcp://HOST:PORT`` scheduler refuses connections (Dask's
    own client would retry for SCHEDULER_TIMEOUT_S); other schemes are left to Dask."""
    if not scheduler.startswith(TCP_SCHEME):
        return
    host, _, port = scheduler[len(TCP_SCHEME):].rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), SCHEDULER_PROBE_S):
            return
    except (OSError, ValueError) as exc:
        raise ConfigError("command line", "--scheduler", scheduler,
                          "the address of a running Dask scheduler, tcp://HOST:PORT (as "
                          f"`python -m dask scheduler` prints it): {exc}") from exc


def _connect(client_cls: Any, scheduler: str) -> Any:
    """A client of the scheduler at ``scheduler``, or a ConfigError saying why not."""
    try:
        return client_cls(scheduler, timeout=SCHEDULER_TIMEOUT_S)
    except (OSError, ValueError, TypeError) as exc:  # bad address, nothing listening, timeout
        raise ConfigError("command line", "--scheduler", scheduler,
                          "the address of a running Dask scheduler, tcp://HOST:PORT (as "
                          f"`python -m dask scheduler` prints it): {exc}") from exc


def run_cases(cases: list[dict[str, Any]], scenario: Path, out: Path, timeout_s: float,
              scheduler: str | None = None, workers: int | None = None,
              progress: Progress | None = None,
              notice: Callable[[str], None] = print,
              record: str = RECORD_STANDARD) -> list[dict[str, Any]]:
    """Every case's row, in case order (module docstring; ``record``: the cases' record
    level, bench.results.record)."""
    from distributed import Client, LocalCluster, as_completed

    from bench.campaign.warm_workers import ZygotePlugin

    cases_dir = out / "cases"
    cases_dir.mkdir(parents=True, exist_ok=True)
    _clear_attempts(cases_dir)
    rows = done_rows(cases_dir, cases)
    total = len(cases)
    for n, i in enumerate(sorted(rows), start=1):
        if progress is not None:
            progress(n, total, rows[i])
    todo = [c for c in cases if c["index"] not in rows]
    if not todo:
        return [rows[c["index"]] for c in cases]
    n_workers = workers or available_cpus()
    env: dict[str, str] = {}
    if scheduler is not None or PROCESSES_PER_CASE * min(n_workers, len(todo)) > available_cpus():
        # more processes than CPUs (a cluster's workers are one per CPU): block, do not poll
        env[LOCKSTEP_SPIN_ENV] = "0"
    with contextlib.ExitStack() as stack:
        if scheduler is None:
            # Ctrl-C reaches the terminal's whole process group: the workers ignore it (an
            # ignored signal stays ignored in the processes they start) and this process
            # stops them; each case's run is in a session of its own
            with _sigint_ignored():
                cluster = stack.enter_context(LocalCluster(
                    n_workers=min(n_workers, len(todo)), threads_per_worker=1,
                    processes=True, dashboard_address=None, silence_logs=DASK_LOG_LEVEL))
            client = stack.enter_context(Client(cluster))
        else:
            client = stack.enter_context(_connect(Client, scheduler))
        token = uuid.uuid4().hex[:8]  # keys unique on a shared scheduler
        plugin = ZygotePlugin(token)  # each worker starts its cases warm
        client.register_plugin(plugin)
        stack.callback(_unregister, client, plugin.name)

        def submit(c: dict[str, Any], attempt: int) -> Any:
            return client.submit(run_case, c, str(scenario), str(cases_dir), timeout_s, env,
                                 attempt, plugin.name, record,
                                 key=f"case-{c['name']}-{token}-{attempt}", pure=False)

        futures = {submit(c, 1): (c, 1) for c in todo}
        done = len(rows)
        pending = as_completed(list(futures))
        try:
            for f in pending:
                c, attempt = futures.pop(f)
                try:
                    row = f.result()
                except Exception as exc:
                    why = f"{type(exc).__name__}: {exc}"
                    if attempt <= RETRIES:
                        notice(f"case {c['name']}: attempt {attempt} failed ({why}); retrying")
                        nxt = submit(c, attempt + 1)
                        futures[nxt] = (c, attempt + 1)
                        pending.add(nxt)
                        continue
                    row = error_row(c, f"{why} (after {attempt} attempts)", attempt)
                rows[c["index"]] = row
                done += 1
                if progress is not None:
                    progress(done, total, row)
        except BaseException:
            for f in futures:
                f.cancel()
            raise
    _clear_attempts(cases_dir)  # a lost worker's attempt, stopped with it
    return [rows[c["index"]] for c in cases]
