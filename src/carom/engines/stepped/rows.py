"""The contact rows' declared layout: the integer columns both dimensions' rows share.

A rigid engine keeps its contacts as rows of two arrays, floats (the points, normals and
accumulated impulses; each dimension its own) and integers, whose first columns are the same
in 2D and 3D, so that what reads them alike (islands, colouring, the impacts' bookkeeping)
reads them from here: the two bodies, their two pieces, how many points, the points' feature
ids from :data:`I_ID0`, and after those the flags.
"""

from __future__ import annotations

__all__ = [
    "FLAG_EXACT",
    "I_BODY_A",
    "I_BODY_B",
    "I_COUNT",
    "I_ID0",
    "I_PIECE_A",
    "I_PIECE_B",
    "flags_column",
]

I_BODY_A = 0
I_BODY_B = 1
I_PIECE_A = 2
I_PIECE_B = 3
I_COUNT = 4  # points in the manifold
I_ID0 = 5  # the points' feature ids: I_ID0 + j
#: bit of the flags: the contact was solved exactly this step (an isolated impact)
FLAG_EXACT = 1


def flags_column(max_points: int) -> int:
    """The column of the flags in rows of manifolds of up to ``max_points`` points."""
    return I_ID0 + max_points
