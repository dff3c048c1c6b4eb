"""Every option and argument of every command line has help text (``--help`` explains it)."""

from __future__ import annotations

import argparse
import contextlib

import pytest

from bench.operator import flood, hostile
from bench.operator.campaign import add_arguments
from bench.operator.cli import build_parser
from flight_sw import __main__ as fsw_main


def _parsers() -> dict[str, argparse.ArgumentParser]:
    """thruster-hil and each subcommand, campaign's own, flood, hostile, the flight software."""
    top = build_parser()
    out = {"thruster-hil": top}
    for action in top._actions:  # the documented way to reach subparsers is this attribute
        if isinstance(action, argparse._SubParsersAction):
            out.update({f"thruster-hil {n}": p for n, p in action.choices.items()})
    campaign = argparse.ArgumentParser()
    add_arguments(campaign, default_jobs=1)
    out["campaign"] = campaign
    return out


def _captured(main: object, monkeypatch: pytest.MonkeyPatch) -> argparse.ArgumentParser:
    """The parser a module's main() builds (parse_args is intercepted before it runs)."""
    seen: list[argparse.ArgumentParser] = []

    def grab(self: argparse.ArgumentParser, *args: object, **kwargs: object) -> None:
        seen.append(self)
        raise SystemExit(0)

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", grab)
    with contextlib.suppress(SystemExit):  # some mains turn it into their exit code
        main([])  # type: ignore[operator]
    return seen[0]


def test_every_option_has_help(monkeypatch: pytest.MonkeyPatch) -> None:
    """No option or positional argument of any tool lacks help text."""
    parsers = _parsers()
    for name, mod in (("flood", flood), ("hostile", hostile), ("flight_sw", fsw_main)):
        parsers[name] = _captured(mod.main, monkeypatch)
    missing = [f"{name}: {'/'.join(a.option_strings) or a.dest}"
               for name, p in parsers.items() for a in p._actions
               if not isinstance(a, (argparse._HelpAction, argparse._SubParsersAction))
               and not a.help]
    assert missing == []
