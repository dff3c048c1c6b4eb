"""The FAULT_CMD builder of ``thruster-hil inject``: bad input names the value."""

from __future__ import annotations

import re
from typing import Any

import pytest

from bench.operator.inject import KIND_CODES, FaultCommand, cansend_string
from bench.station.faults import fault_from_command
from dbc.database import load_database
from dbc.errors import ConfigError
from dbc.icd import Icd

N_THRUSTERS = 8
ICD = Icd.from_database(load_database())
IMU_RATE_ID = ICD.frame_id["IMU_RATE"]


def _cmd(kind: str, target: int, param: float = 0.0) -> dict[str, float]:
    return {"Action": 1, "FaultType": KIND_CODES[kind], "Target": target, "Duration": 0.0,
            "Param": param}


def test_unknown_kind_is_a_config_error_naming_it() -> None:
    """A misspelt kind raises ConfigError (exit 2) with the value and the valid kinds."""
    with pytest.raises(ConfigError, match=r"kind = 'stuk_open': expected one of .*stuck_open"):
        FaultCommand("stuk_open", 1)


def test_every_kind_encodes_to_a_fault_cmd_frame() -> None:
    """Every known kind builds a FAULT_CMD frame string for cansend (ID#8 data bytes)."""
    for kind in KIND_CODES:
        can_id, data = cansend_string(FaultCommand(kind, 0), counter=0).split("#")
        assert int(can_id, 16) > 0 and len(bytes.fromhex(data)) == 8, kind


@pytest.mark.parametrize("kind, target, param, says", [
    ("stuck_open", N_THRUSTERS, 0.0, "Target = 8: expected a thruster index 0..7"),
    ("bias_jump", 7, 0.0, "Target = 7: expected a sensor index"),
    ("drop", IMU_RATE_ID, 1.5, "Param = 1.5: expected a probability in (0, 1]"),
    ("drop", 0x7FF, 0.5, "Target = 2047: expected the CAN ID of a DBC message"),
    ("delay", IMU_RATE_ID, 0.0, "Param = 0.0: expected a delay > 0 s"),
])
def test_fault_cmd_the_bench_cannot_apply_says_why(kind: str, target: int, param: float,
                                                   says: str) -> None:
    """A live FAULT_CMD with a target or parameter this bench lacks: ConfigError naming it."""
    with pytest.raises(ConfigError, match=re.escape(f"FAULT_CMD: {says}")):
        fault_from_command(_cmd(kind, target, param), ICD, N_THRUSTERS, 0.0)


def test_unknown_fault_type_code_is_refused() -> None:
    """A FaultType code outside the VAL_ table: ConfigError naming the code."""
    cmd = {**_cmd("drop", IMU_RATE_ID), "FaultType": max(ICD.fault_kinds) + 1}
    with pytest.raises(ConfigError, match="FaultType"):
        fault_from_command(cmd, ICD, N_THRUSTERS, 0.0)


def test_applicable_fault_cmd_builds_its_fault() -> None:
    """stuck_open on thruster 3 and drop (p 0.25) on IMU_RATE give the matching FaultSpec."""
    f = fault_from_command(_cmd("stuck_open", 3), ICD, N_THRUSTERS, 1.5)
    assert (f.kind, f.thruster, f.t_s) == ("stuck_open", 3, 1.5)
    d = fault_from_command(_cmd("drop", IMU_RATE_ID, 0.25), ICD, N_THRUSTERS, 0.0)
    assert (d.message, d.params["probability"]) == ("IMU_RATE", 0.25)


@pytest.mark.parametrize("option, kw", [("--target", {"target": 1 << 12}),
                                        ("--duration", {"duration_s": -1.0}),
                                        ("--param", {"param": -3.0})])
def test_out_of_dbc_range_options_are_config_errors(option: str, kw: dict[str, Any]) -> None:
    """Values outside FAULT_CMD's DBC ranges: ConfigError naming the option (exit 2)."""
    args: dict[str, Any] = {"kind": "degraded", "target": 1, **kw}
    with pytest.raises(ConfigError, match=re.escape(option)):
        FaultCommand(**args)
