"""setuptools finds the packages: every package under shadowvol/ and raytrace/, so a new one can
never be left out of the wheel (a hand-written list once dropped the batch's dataset package and
broke every command).  Everything else is in pyproject.toml.  The two data folders at the top, shaders/
and scenes/, ship inside the package as shadowvol.shaders and shadowvol.scenes (package-dir there);
pyproject's [tool.setuptools] cannot combine a `find` with those two mapped names, hence this file.
"""

from setuptools import find_packages, setup

setup(packages=find_packages(include=["shadowvol", "shadowvol.*", "raytrace", "raytrace.*"])
      + ["shadowvol.shaders", "shadowvol.scenes"])
