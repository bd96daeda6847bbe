"""The event-driven engine's codes: event kinds, why the loop returned, and the slots of its
running counts and sums. Plain integers, read as constants by the kernels."""

from __future__ import annotations

SHELL_MARGIN = 1.0 - 1e-9  # the fraction of the shell a body may use

EV_NONE = 0
EV_PAIR = 1
EV_WALL = 2  # other = face: 2k lower, 2k + 1 upper wall of axis k; 2 dim + p plane p
EV_SHELL = 3

# why the loop (carom.engines.edmd.loop.run_frames) returned
DONE = 0
LOG_FULL = 1
MAX_EVENTS = 2
LISTS_FULL = 3  # a neighbour list is full: grow the lists
CELLS_FULL = 4  # a cell row is full: grow the rows

# counts[]
C_EVENTS = 0
C_PAIR = 1
C_WALL = 2
C_SHELL = 3
C_STALE = 4
C_TC = 5  # collisions made elastic by the TC model
C_REST = 6  # bodies brought to rest on a wall or plane
C_FLOOR = 7  # pair collisions whose parting speed the floor raised (collide_pair)
# sums[]
S_VIRIAL = 0  # sum over collisions of J . r  [J s] (pairs: r = x1 - x2; walls: r = x)
S_KE_LOST = 1  # kinetic energy dissipated by the impact laws [J]
S_KE_GIVEN = 2  # kinetic energy given by the parting-speed floor [J] (collide_pair)
S_WORK = 3  # kinetic energy given to bodies between calls (their new motion, impulses) [J]
