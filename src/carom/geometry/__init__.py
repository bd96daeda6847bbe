"""World-free geometry kernels: times of impact (and, for the rigid-body engine, contact
manifolds), one algorithm per module, named ``<operation>_<shape1>_<shape2>``."""

from carom.jit import kernel_cache

with kernel_cache():
    from carom.geometry import (  # noqa: F401
        bvh,
        manifold2d,
        manifold3d,
        overlaps,
        rays,
        rotation,
        toi,
    )
