"""`python -m raytrace`: the same as the `raytrace` command."""

import sys

from raytrace.cli import main

sys.exit(main())
