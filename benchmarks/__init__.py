"""shadowvol's benchmarks: a package of the checkout, outside the wheel, run from its root.

    python -m benchmarks.run             # every benchmark; writes BENCHMARKS.md and its plot
    python -m benchmarks.run --quick     # a smoke run on tiny scenes
    python -m benchmarks.bench_masks     # one benchmark alone (each bench_*/profile_* module)

Running as modules from the checkout's root puts that checkout first on the path, so the code
measured is the checkout's, installed or not.  What was kept, dropped and why:
`benchmarks/OPTIMISATIONS.md`.
"""
