"""JUnit XML of a run, for CI servers: one test case per expectation, failures where they fail.

In: a run's summary.json content, its folder, when the summary was written and the host.
Out: XML in the JUnit layout of Ant's ``junit`` task (``<testsuites>``, ``<testsuite>``,
``<testcase>`` with ``<failure>`` or ``<error>``), which Jenkins, GitLab and GitHub's test
reporters read and show natively:

- one ``<testsuite>`` per run, named after the scenario: ``tests``, ``failures``,
  ``errors``, ``time`` (the run's wall time [s]), ``timestamp`` (when summary.json was
  written, UTC), ``hostname``; ``<properties>`` with the scenario file, mode, seed, bus,
  verdict, run folder and each requirement ID (``requirement.<row>``); the abnormal lines
  (SAFE, restarts, drops, rejects ...) and the warnings in ``<system-out>``;
- a ``<testcase>`` ``converged`` (every run checks that the attitude error ends inside the
  settling band) and one per expectation row of summary.json, classname
  ``thruster-hil.<scenario>``; a failed one has a ``<failure>`` whose message gives the
  value, the bound and the requirement ID; each case's ``<system-out>`` has its value,
  bound, requirement and the run folder;
- a run that did not complete (a process died, a refused input, a stop signal) or whose
  bus was compromised (forged frames) gets a ``<testcase>`` ``run`` with an ``<error>``
  saying why; so does a run with no summary at all (``error_text``). Its checks are
  reported ``<skipped>`` ("not judged"), not failed: figures from part of a run say
  nothing about a requirement, and CI would otherwise show each one failed.

:func:`junit_xml` is pure (the caller reads the files); :func:`write_junit` is its edge:
it reads the run folder's summary.json (its modification time is the ``timestamp``, so
``thruster-hil report --junit`` writes the same file again) and writes the XML. Written
with the standard library's ElementTree (escaping, UTF-8).
"""

from __future__ import annotations

import json
import math
import socket
import xml.etree.ElementTree as ET
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

SUITES_NAME = "thruster-hil"
CLASS_PREFIX = "thruster-hil."
NO_TIME = "0"
CONVERGED = "converged"


def _number(x: Any) -> str:
    """A value as text: numbers with up to 6 significant digits, n/a for none."""
    if isinstance(x, bool) or x is None:
        return "n/a" if x is None else str(x).lower()
    if isinstance(x, (int, float)):
        return "nan" if isinstance(x, float) and math.isnan(x) else f"{x:.6g}"
    return str(x)


def _cases(summary: dict[str, Any]) -> list[dict[str, Any]]:
    """The checks of a run: convergence, then each expectation row, as test-case records."""
    reqs = summary.get("requirements") or {}
    cases: list[dict[str, Any]] = []
    if summary.get("converged") is not None:
        band = summary.get("settling_band_deg")
        ok = bool(summary["converged"])
        final = summary.get("final_attitude_error_deg")
        cases.append({
            "name": CONVERGED, "pass": ok, "req": reqs.get(CONVERGED),
            "text": f"the attitude error {'ended' if ok else 'did not end'} inside the "
                    f"{_number(band)} deg settling band (final error {_number(final)} deg)",
            "value": final, "max": band,
            "labels": ("final_attitude_error_deg", "settling_band_deg"),
        })
    for row in summary.get("expectations") or []:
        cases.append({
            "name": str(row["name"]), "pass": bool(row["pass"]), "req": row.get("req"),
            "text": f"{row['name']} = {_number(row['value'])}, max {_number(row['max'])}"
                    + (f" ({row['note']})" if row.get("note") else ""),
            "value": row["value"], "max": row["max"],
            "labels": (str(row["name"]), "max"),  # the name carries the unit (_s, _deg, _m)
        })
    return cases


def _run_error(summary: dict[str, Any] | None, error_text: str | None) -> str | None:
    """Why the run itself is an error (not a failed check), or None."""
    if summary is None:
        return error_text or "no summary.json"
    reasons = []
    if summary.get("ended") not in (None, "completed"):
        reasons.append(f"the run ended: {summary.get('ended')}")
    if summary.get("error"):
        reasons.append(str(summary["error"]))
    if summary.get("refused"):
        reasons.append(f"refused: {summary['refused']}")
    if summary.get("compromised"):
        reasons.append(f"bus compromised: {summary['compromised']}")
    return "; ".join(reasons) or None


def junit_xml(summary: dict[str, Any] | None, run_dir: Path, timestamp: str, hostname: str,
              scenario: str | None = None, error_text: str | None = None) -> bytes:
    """The JUnit XML of a run (module docstring). ``timestamp``: ISO 8601 without a zone
    (UTC); ``scenario``: the suite's name when there is no summary to take it from."""
    name = str((summary or {}).get("scenario") or scenario or "run")
    classname = CLASS_PREFIX + name
    cases = _cases(summary) if summary is not None else []
    error = _run_error(summary, error_text)
    judged = error is None
    failures = sum(1 for c in cases if not c["pass"]) if judged else 0
    skipped = 0 if judged else len(cases)
    errors = 1 if error is not None else 0
    wall_s = (summary or {}).get("wall_time_s")
    time_s = _number(wall_s) if isinstance(wall_s, (int, float)) else NO_TIME
    root = ET.Element("testsuites", name=SUITES_NAME, tests=str(len(cases) + errors),
                      failures=str(failures), errors=str(errors), time=time_s)
    suite = ET.SubElement(root, "testsuite", name=name, package=SUITES_NAME, id="0",
                          tests=str(len(cases) + errors), failures=str(failures),
                          errors=str(errors), skipped=str(skipped), time=time_s,
                          timestamp=timestamp, hostname=hostname)
    props = ET.SubElement(suite, "properties")
    s = summary or {}
    for key in ("scenario_file", "mode", "seed", "bus", "verdict"):
        if s.get(key) is not None:
            ET.SubElement(props, "property", name=key, value=str(s[key]))
    ET.SubElement(props, "property", name="run_folder", value=str(run_dir))
    for row, req in sorted((s.get("requirements") or {}).items()):
        ET.SubElement(props, "property", name=f"requirement.{row}", value=str(req))
    for c in cases:
        case = ET.SubElement(suite, "testcase", name=c["name"], classname=classname,
                             time=NO_TIME)
        req = f" [{c['req']}]" if c["req"] else ""
        if not judged:
            ET.SubElement(case, "skipped", message="not judged: the run did not complete "
                          "(see the error of test case 'run')")
        elif not c["pass"]:
            failure = ET.SubElement(case, "failure", type="expectation",
                                    message=f"{c['text']}{req}")
            failure.text = f"{c['text']}{req}\nrun folder: {run_dir}"
        out = ET.SubElement(case, "system-out")
        value_label, max_label = c["labels"]
        out.text = (f"{value_label}: {_number(c['value'])}\n{max_label}: {_number(c['max'])}\n"
                    f"requirement: {c['req'] or 'none'}\nrun folder: {run_dir}")
    if error is not None:
        case = ET.SubElement(suite, "testcase", name="run", classname=classname, time=NO_TIME)
        err = ET.SubElement(case, "error", type="run", message=error)
        err.text = f"{error}\nrun folder: {run_dir}"
    lines = [f"verdict: {s.get('verdict', 'n/a')}"]
    lines += [f"ABNORMAL {x}" for x in s.get("abnormal") or []]
    lines += [f"WARNING {w}" for w in s.get("warnings") or []]
    ET.SubElement(suite, "system-out").text = "\n".join(lines)
    ET.SubElement(suite, "system-err").text = ""
    ET.indent(root)
    return bytes(ET.tostring(root, encoding="utf-8", xml_declaration=True)) + b"\n"


def write_junit(path: Path, run_dir: Path, scenario: str | None = None,
                error_text: str | None = None) -> None:
    """Write the JUnit XML of the run in ``run_dir`` to ``path`` (module docstring); a
    folder without a (readable) summary.json gives one error test case with
    ``error_text``."""
    summary_path = run_dir / "summary.json"
    summary: dict[str, Any] | None = None
    when = datetime.now(timezone.utc)
    try:
        loaded = json.loads(summary_path.read_text(encoding="utf-8"))
        if isinstance(loaded, dict):
            summary = loaded
            when = datetime.fromtimestamp(summary_path.stat().st_mtime, timezone.utc)
    except (OSError, ValueError):
        pass
    stamp = when.replace(tzinfo=None, microsecond=0).isoformat()
    path.write_bytes(junit_xml(summary, run_dir, stamp, socket.gethostname(), scenario,
                               error_text))
