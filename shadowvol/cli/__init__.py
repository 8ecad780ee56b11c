"""The command line of both tools: `shadowvol` (`shadowvol.cli.main`) and the one exit-status
table (`shadowvol.cli.status`) that `raytrace` shares.  Importing this package imports no GL."""


def main(argv=None) -> int:
    """`shadowvol ...` (see `shadowvol.cli.main`)."""
    from shadowvol.cli.main import main as _main
    return _main(argv)
