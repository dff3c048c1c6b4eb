"""The ``thruster-hil`` console script: the flight software's prestart first, then the console.

A ``run`` with the default flight software (no ``--fsw-cmd``) starts its prestart
(bench.operator.fsw_prestart) before anything else is imported, so that the flight
software's imports run on the other core while the console imports and parses the
scenario; then the console (bench.operator.cli) runs with it. This module imports the
standard library only until then. Any other command goes straight to the console.
"""

from __future__ import annotations

import signal
import sys

from bench.operator.fsw_prestart import DEFAULT_FSW_MODULE, FswPrestart

HELP_OPTIONS = ("-h", "--help")
FSW_CMD_OPTION = "--fsw-cmd"
MIN_ABBREVIATION = len("--f")  # argparse takes any unambiguous prefix of an option
EXIT_INTERRUPTED = 128 + signal.SIGINT  # as the console reports Ctrl-C


def _names_fsw_cmd(arg: str) -> bool:
    """``--fsw-cmd``, ``--fsw-cmd=...`` or an abbreviation argparse takes for it."""
    name = arg.split("=", 1)[0]
    return len(name) >= MIN_ABBREVIATION and FSW_CMD_OPTION.startswith(name)


def wants_prestart(argv: list[str]) -> bool:
    """Whether the command line ``argv`` runs the default flight software: ``run`` without
    ``--fsw-cmd`` (nor help). A wrong guess costs only the prestart's imports: a run whose
    flight-software command is not its own starts that command."""
    return (argv[:1] == ["run"] and FswPrestart.wanted()
            and not any(_names_fsw_cmd(a) or a in HELP_OPTIONS for a in argv[1:]))


def main() -> int:
    """Entry point of the ``thruster-hil`` console script."""
    argv = sys.argv[1:]
    prestart: FswPrestart | None = None
    if wants_prestart(argv):
        try:
            prestart = FswPrestart(DEFAULT_FSW_MODULE)
        except OSError:  # no process to spare: the flight software starts cold
            prestart = None
    try:
        from bench.operator.cli import main as cli_main

        return cli_main(argv, prestart)
    except KeyboardInterrupt:  # Ctrl-C before the console handles it (its imports)
        print("\nthruster-hil: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        if prestart is not None:
            prestart.close()


if __name__ == "__main__":
    sys.exit(main())
