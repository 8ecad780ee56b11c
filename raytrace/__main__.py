"""`python -m raytrace`: the same as the `raytrace` command, whose code is the command line's
(`shadowvol.cli.raytrace`): the one import of the command line from the ray tracer."""

import sys

from shadowvol.cli import raytrace_entry

sys.exit(raytrace_entry())
