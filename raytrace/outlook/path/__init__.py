"""The path tracer's family: `pathtrace` (the integrator), `pathstate` (the path state's
precision, PathWorld), `mis` (NEE against BSDF sampling), `sobol` (per-pixel Owen-scrambled
Sobol samples), `pathkernels` and `pathstages` (the shading compiled with numba)."""
