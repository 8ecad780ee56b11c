"""The outlook: global illumination, beyond what the witness checks — Whitted recursion
(`whitted`, one pixel's ray tree `raytree`), the path tracer's family (`path`), Jensen's
photon map (`photon`, `photonmap`), radiosity (`radiosity`, `contacts`, `formrays`), the
analytic direct light (`direct`), and what they share (`brdf`, `sampling`, `progress`).

It may import the witness (`raytrace.masks`, `raytrace.backends`, ...); the witness never
imports it (tests/test_architecture.py).
"""
