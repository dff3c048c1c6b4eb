"""The FAULT_CMD builder of ``thruster-hil inject``: bad input names the value."""

from __future__ import annotations

import pytest

from bench.inject import KIND_CODES, FaultCommand, cansend_string
from dbc.errors import ConfigError


def test_unknown_kind_is_a_config_error_naming_it() -> None:
    """A misspelt kind raises ConfigError (exit 2) with the value and the valid kinds."""
    with pytest.raises(ConfigError, match=r"kind = 'stuk_open': expected one of .*stuck_open"):
        FaultCommand("stuk_open", 1)


def test_every_kind_encodes_to_a_fault_cmd_frame() -> None:
    """Every known kind builds a FAULT_CMD frame string for cansend (ID#8 data bytes)."""
    for kind in KIND_CODES:
        can_id, data = cansend_string(FaultCommand(kind, 0), counter=0).split("#")
        assert int(can_id, 16) > 0 and len(bytes.fromhex(data)) == 8, kind
