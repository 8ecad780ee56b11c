"""`python -m shadowvol`: the same as the `shadowvol` command."""

import sys

from shadowvol.cli import shadowvol_entry

sys.exit(shadowvol_entry())
