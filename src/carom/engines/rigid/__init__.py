"""The time-stepped rigid-body engine for 2D bodies with rotation (docs/rigid.md).

``settings`` (what a user may set), ``model`` (constants and state), ``motion`` (placing
pieces, free flight), ``broadphase`` (swept boxes in a hashed grid), ``contacts`` (manifolds,
warm start), ``islands`` (roles, sleep), ``impacts`` (isolated impacts solved exactly at the
time of impact), ``solver`` (the soft step in named stages), and ``driver`` (the
:class:`carom.engines.base.Engine` that a World runs).
"""

from carom.jit import kernel_cache

with kernel_cache():
    from carom.engines.rigid import (  # noqa: F401
        broadphase,
        contacts,
        impacts,
        islands,
        motion,
        solver,
    )
