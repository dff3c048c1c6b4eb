"""The ICD's facts read from the DBC: the values both sides use instead of literals."""

from __future__ import annotations

import cantools
import pytest

from dbc.database import DBC_PATH, load_database
from dbc.errors import IcdError
from dbc.icd import BENCH, FSW, Icd

DB = load_database()
NS_PER_MS = 1_000_000


def test_command_layout_comes_from_the_thr_cmd_frames() -> None:
    """Command frames in ID order, on-time signals numbered across them, period from the DBC."""
    icd = Icd.from_database(DB)
    cmds = sorted((m for m in DB.messages if m.name.startswith("THR_CMD_")),
                  key=lambda m: m.frame_id)
    assert icd.command_frames == tuple(m.name for m in cmds)
    per = [len([s for s in m.signals if s.name.startswith("OnTime_T")]) for m in cmds]
    assert icd.thrusters_per_command == per[0] and set(per) == {per[0]}
    assert icd.max_thrusters == sum(per)
    assert icd.control_period_ns == cmds[0].cycle_time * NS_PER_MS
    assert icd.command_frames_for(5) == icd.command_frames[:2]
    assert icd.command_frames_for(icd.max_thrusters) == icd.command_frames


def test_counters_periods_and_senders_match_the_dbc() -> None:
    """Counter widths are 2**length; periods and senders are the DBC's, per message."""
    icd = Icd.from_database(DB)
    for m in DB.messages:
        assert icd.period_ns[m.name] == (m.cycle_time or 0) * NS_PER_MS
        assert icd.sender[m.name] == m.senders[0]
        assert icd.name_by_id[m.frame_id] == m.name
    sync_cycle = DB.get_message_by_name("SYNC").get_signal_by_name("Cycle")
    assert icd.sync_cycle_modulus == 1 << sync_cycle.length
    assert "SYNC" in icd.sent_by(BENCH) and "FSW_STATUS" in icd.sent_by(FSW)


def test_value_tables_name_modes_faults_and_flags() -> None:
    """Value tables give the modes, every fault kind, failure kinds and single-bit flags."""
    icd = Icd.from_database(DB)
    assert {"BOOT", "NOMINAL", "SAFE"} <= set(icd.modes)
    table = DB.get_message_by_name("FAULT_CMD").get_signal_by_name("FaultType").choices
    assert set(icd.fault_kinds.values()) == {str(v) for k, v in table.items() if k != 0}
    assert all(bit & (bit - 1) == 0 for bit in icd.health_flags.values())
    assert icd.no_failed_thruster == 31 and icd.fault_cmd_counter_none == 15


def test_a_dbc_without_a_needed_value_table_is_refused_naming_it() -> None:
    """Removing FSW_STATUS.Mode's VAL_ line gives an IcdError that names the signal."""
    text = DBC_PATH.read_text(encoding="utf-8")
    lines = [ln for ln in text.splitlines() if not ln.startswith("VAL_ 144 Mode")]
    db = cantools.database.load_string("\n".join(lines), database_format="dbc")
    with pytest.raises(IcdError, match=r"FSW_STATUS\.Mode"):
        Icd.from_database(db)


def test_the_flight_softwares_modes_and_flags_are_the_dbcs() -> None:
    """flight_sw.modes' Mode, FdirFlag and SensorFlag equal the DBC's value tables."""
    from flight_sw.modes import FdirFlag, Mode, SensorFlag

    icd = Icd.from_database(DB)
    assert {m.name: int(m) for m in Mode} == dict(icd.modes)
    assert {f.name.lower(): int(f) for f in FdirFlag} == dict(icd.fdir_flags)
    assert {f.name.lower(): int(f) for f in SensorFlag} == dict(icd.sensor_flags)


def test_fault_kinds_are_the_dbcs_fault_types() -> None:
    """dbc.faults names exactly the DBC's FAULT_CMD.FaultType kinds, grouped without overlap."""
    from dbc import faults

    icd = Icd.from_database(DB)
    assert sorted(faults.FAULT_KINDS) == sorted(icd.fault_kinds.values())
    groups = (faults.THRUSTER_KINDS, faults.SENSOR_KINDS, faults.BUS_KINDS)
    assert sum(len(g) for g in groups) == len(set().union(*groups))
    assert set(faults.FRAME_KINDS) >= faults.REALTIME_BUS_KINDS
