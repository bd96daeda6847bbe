"""Closed-form impulse laws: two spheres (smooth, rough, Walton's friction) in NumPy
(:mod:`carom.laws.spheres`) and as Numba kernels (:mod:`carom.laws.kernels`), and the point
impulse between rigid bodies with inertia (:mod:`carom.laws.point_impulse`)."""

from carom.jit import kernel_cache

with kernel_cache():
    from carom.laws import batch, kernels, rigid_impact  # noqa: F401
