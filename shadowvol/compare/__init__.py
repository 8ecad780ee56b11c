"""The comparison wing: raster against the ray tracer (and pyrender's shadow maps).

`maskdiff` defines a mask edge and counts mismatches (shared with the tests), `comparison` runs
both renderers and draws the difference, `pyrender_peer` converts scenes to and from pyrender.
"""

from shadowvol.compare.comparison import Comparison, LightComparison, compare

__all__ = ["Comparison", "LightComparison", "compare"]
