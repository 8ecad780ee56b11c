"""The command line of both tools: `shadowvol` (`shadowvol.cli.main`), `raytrace`
(`shadowvol.cli.raytrace`) and the one exit-status table (`shadowvol.cli.status`) they share.

The console scripts and `python -m shadowvol` / `python -m raytrace` enter through
`shadowvol_entry` and `raytrace_entry` here: they catch Ctrl-C and SIGTERM while the commands'
modules are still being imported (GL, numpy, Pillow), which would otherwise print a traceback,
and report a signal once.  Importing this package imports no GL.
"""

from __future__ import annotations

import importlib
import sys

from shadowvol import errors, signals


def shadowvol_entry(argv=None) -> int:
    """`shadowvol ...` (see `shadowvol.cli.main`)."""
    return _enter("shadowvol.cli.main", argv)


def raytrace_entry(argv=None) -> int:
    """`raytrace ...` (see `shadowvol.cli.raytrace`)."""
    return _enter("shadowvol.cli.raytrace", argv)


def _enter(module: str, argv) -> int:
    with signals.handled(restore=False):  # the process ends with the command
        try:
            entry = importlib.import_module(module).main
            signals.raise_pending()  # one that an import swallowed
            code = entry(argv)
            if code not in (errors.INTERRUPTED, errors.TERMINATED):  # else reported already
                signals.raise_pending()
            signals.finished()
            return code
        except (KeyboardInterrupt, signals.Terminated, Exception) as exc:
            signals.finished()
            exc = signals.pending() or exc  # an interrupt may surface as ImportError
            if isinstance(exc, (KeyboardInterrupt, signals.Terminated)):
                print(f"error: {errors.message(exc)}", file=sys.stderr)
                return errors.status_of(exc)
            raise
