"""The argument blocks that the subcommands of both tools share, each written once, and what
the shared `--outputs` list names (`outputs_named`).

A block takes the parser and, where commands word it differently, the help or metavar; the
flags, destinations and defaults stay the block's.  Every subcommand's --help ends with the one
exit-status table (`command`).
"""

from __future__ import annotations

import argparse

from shadowvol import memory
from shadowvol.cli import status
from shadowvol.errors import InputError
from shadowvol.frame import GROUND_TRUTH, LAYERS, check_outputs
from shadowvol.scene import SceneError, shorten

SCENE_HELP = "scene file (.toml or .json)"
BACKEND_HELP = ("triangle intersection: 'embree' (fast, float32) or 'numpy' (the float64 "
                "reference, for small scenes) (default: embree)")


class Parser(argparse.ArgumentParser):
    """argparse's parser whose usage errors are one line, ending with where the help is (the
    usage block it would print first is --help's); the exit status is still 2 (bad input)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def command(subparsers, name: str, *, help: str, description: str,
            epilog: str = status.EPILOG) -> argparse.ArgumentParser:
    """A subcommand whose --help keeps its epilog's line breaks (it ends with the statuses)."""
    return subparsers.add_parser(name, help=help, description=description, epilog=epilog,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)


def scene(p: argparse.ArgumentParser, help: str = SCENE_HELP, **kwargs) -> None:
    """The SCENE positional (`render` takes several: nargs="*")."""
    p.add_argument("scene", metavar="SCENE", help=help, **kwargs)


def output(p: argparse.ArgumentParser, metavar: str, help: str, required: bool = True,
           **kwargs) -> None:
    """`-o/--output`: what the command writes (a file, or a folder)."""
    p.add_argument("-o", "--output", required=required, metavar=metavar, help=help, **kwargs)


def backend(p: argparse.ArgumentParser, choices: tuple[str, ...], help: str = BACKEND_HELP) -> None:
    """The ray tracer's `--backend` (choices: `raytrace.backends.BACKENDS`, passed in so that
    the `shadowvol` commands never import the ray tracer)."""
    p.add_argument("--backend", choices=choices, default="embree", help=help)


def memory_budget(p: argparse.ArgumentParser) -> None:
    """`--memory-budget SIZE`, of the commands that check one (`shadowvol.memory.check`)."""
    p.add_argument(
        "--memory-budget", metavar="SIZE", default=None,
        help=f"refuse an image whose estimated memory (shadowvol.memory) exceeds SIZE, e.g. "
             f"12GiB (default: ${memory.ENV}, else {memory.DEFAULT_FRACTION * 100:.0f}%% of "
             f"this machine's memory)")


def ground_truth(p: argparse.ArgumentParser, help: str) -> None:
    """`--outputs LIST`: the ground truth added to a mask file (`outputs_named`)."""
    p.add_argument("--outputs", metavar="LIST", default=None, help=help)


GROUND_TRUTH_LIST = ",".join(GROUND_TRUTH + LAYERS)


def outputs_named(text: str | None, flag: str = "--outputs", extra: tuple[str, ...] = ()
                  ) -> tuple[str, ...]:
    """The ground-truth outputs and intrinsic layers named by a command line's comma-separated
    list (`all`: the ground truth, `shadowvol.frame.GROUND_TRUTH`; the layers, each a frame or
    more, by name), in GROUND_TRUTH's then `shadowvol.frame.LAYERS`' order, then those of
    `extra` (outputs one command has besides, e.g. `shadowvol.frame.EXACT_OUTPUTS`; named only,
    never in `all`); () for None.  InputError (exit 2) naming `flag` for an unknown name
    (`shadowvol.frame.check_outputs`)."""
    if text is None:
        return ()
    names = [n.strip() for n in text.split(",") if n.strip()]
    if names == ["all"]:
        return GROUND_TRUTH
    known = GROUND_TRUTH + LAYERS + tuple(extra)
    if not names:
        raise InputError(flag, f"unknown output {shorten(text)} (a comma-separated list of: "
                               f"{', '.join(known)}; or all)")
    try:
        return check_outputs(names, known, key=flag)
    except SceneError as exc:   # the model's check, named as a flag of this command line
        raise InputError(flag, exc.problem) from None


def exr(p: argparse.ArgumentParser, help: str, **kwargs) -> None:
    """`--exr EXR`: the linear image as OpenEXR too."""
    p.add_argument("--exr", metavar="EXR", default=None, help=help, **kwargs)


def seed(p: argparse.ArgumentParser, help: str) -> None:
    """`--seed S` of the seeded ray tracers."""
    p.add_argument("--seed", type=int, default=0, metavar="S", help=help)


def photon(p: argparse.ArgumentParser, kernels: tuple[str, ...]) -> None:
    """The photon map's options on `raytrace render` (kernels:
    `raytrace.outlook.photonmap.KERNELS`)."""
    p.add_argument("--photons", type=int, default=200_000, metavar="N",
                   help="photon mapping: photons shot from the lights (default 200000); its "
                        "eye rays per pixel are --spp's")
    p.add_argument("--knn", type=int, default=None, metavar="K",
                   help="photon mapping: the density estimate over the K nearest photons "
                        "(default 100, unless --radius)")
    p.add_argument("--radius", type=float, default=None, metavar="R",
                   help="photon mapping: the density estimate over the photons within R "
                        "(scene units) instead of the nearest K")
    p.add_argument("--kernel", choices=kernels, default=kernels[0],
                   help=f"photon mapping: the density estimate's kernel (default {kernels[0]})")
    p.add_argument("--final-gather", type=int, default=0, metavar="G",
                   help="photon mapping: G final-gather rays per diffuse hit instead of reading "
                        "the global map there (default 0: none)")
    p.add_argument("--light-samples", type=int, default=1, metavar="N",
                   help="photon mapping: N shadow rays to the area lights per diffuse hit for "
                        "the direct light, averaged (default 1)")
