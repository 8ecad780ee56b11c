"""`python -m shadowvol`: the same as the `shadowvol` command."""

import sys

from shadowvol.cli.main import main

sys.exit(main())
