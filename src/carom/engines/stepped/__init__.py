"""What the 2D and 3D time-stepped rigid-body engines share, one source for both dimensions
(as Rapier builds rapier2d and rapier3d from one): the settings, the step's driver and its
totals, islands and sleep, the contact rows' declared layout, the colouring into lanes and the
soft contact, the kept pairs of the broad phase, warm starting, and the plug's common part.
:mod:`carom.engines.rigid` (2D) and :mod:`carom.engines.rigid3d` (3D) build on it side by
side; neither imports the other.
"""

from carom.jit import kernel_cache

with kernel_cache():
    from carom.engines.stepped import (  # noqa: F401
        broadphase,
        contacts,
        events,
        filters,
        islands,
        joints,
        loads,
        sensors,
        solver,
    )
