"""The exact event-driven engine for spheres and disks (docs/engine.md).

``settings`` (what a user may set), ``model`` and ``state`` (the constants and the changing
arrays), ``predict`` (the next event of a body), ``collide`` (what an event does), ``loop``
(events in time order), ``calendar`` (the event queue), ``neighbours`` (shells and the cell
grid), ``renumber`` (bodies near in space put near in memory), ``prefetch`` and ``lookahead``
(what the loop asks for before it reads it), ``reach`` (new motion given between calls),
and ``driver`` (the :class:`carom.engines.base.Engine` that a World runs).
"""

from carom.jit import kernel_cache

with kernel_cache():
    from carom.engines.edmd import (  # noqa: F401
        calendar,
        collide,
        handle,
        loop,
        neighbours,
        predict,
        reach,
        renumber,
    )
