"""Side by side with pymunk, pybullet and MuJoCo: ``carom compare``.

:func:`compare` runs one scene in carom and its peers, each set up as its own documentation
recommends, and measures every engine with the same :class:`~carom.compare.monitor.Monitor`:
velocity error against the closed form, energy error, penetration, tunnelling and wall time.
"""

from carom.compare.driver import Comparison, compare, peer_scene
from carom.compare.engines import ENGINES

__all__ = ["ENGINES", "Comparison", "compare", "peer_scene"]
