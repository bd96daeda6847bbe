"""The time-stepped rigid-body engine for 3D bodies with rotation (docs/rigid3d.md).

``model`` (constants and state), ``motion`` (rotations, placing pieces, impulses, free
flight), ``cloth`` (balls on a level cloth in closed form), ``broadphase`` (swept boxes in a
hashed grid), ``contacts`` (manifolds, warm start), ``solver`` (the soft step in named stages)
and ``driver`` (the engine a World runs), in the 2D engine's design
(:mod:`carom.engines.rigid`), on the core both share (:mod:`carom.engines.stepped`).
"""

from carom.jit import kernel_cache

with kernel_cache():
    from carom.engines.rigid3d import (  # noqa: F401
        broadphase,
        cloth,
        contacts,
        impacts,
        joints,
        motion,
        queries,
        solver,
    )
