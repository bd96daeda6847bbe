"""The time-stepped rigid-body engine for 2D bodies with rotation (docs/rigid.md), on the
core it shares with 3D (:mod:`carom.engines.stepped`: settings, islands, colouring, kept pairs).

``model`` (constants and state), ``motion`` (placing pieces, free flight), ``broadphase``
(swept boxes in a hashed grid), ``contacts`` (manifolds, warm start), ``impacts`` (isolated
impacts solved exactly at the time of impact), ``solver`` (the soft step in named stages),
``driver`` (the :class:`carom.engines.base.Engine` that a World runs) and ``assemble`` (a
World's bodies, walls and planes as its arrays; its plug).
"""

from carom.jit import kernel_cache

with kernel_cache():
    from carom.engines.rigid import (  # noqa: F401
        broadphase,
        contacts,
        impacts,
        joints,
        motion,
        queries,
        solver,
    )
