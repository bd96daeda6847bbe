"""The contact rows' declared layout: the integer columns both dimensions' rows share.

A rigid engine keeps its contacts as rows of two arrays, floats (the points, normals and
accumulated impulses; each dimension its own) and integers, whose first columns are the same
in 2D and 3D, so that what reads them alike (islands, colouring, the impacts' bookkeeping)
reads them from here: the two bodies, their two pieces, how many points, the points' feature
ids from :data:`I_ID0`, and after those the flags. A point's float columns follow one order
in both dimensions too (:func:`point_layout`).
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = [
    "FLAG_EXACT",
    "FLAG_STRUCK",
    "I_BODY_A",
    "I_BODY_B",
    "I_COUNT",
    "I_ID0",
    "I_PIECE_A",
    "I_PIECE_B",
    "PointLayout",
    "flags_column",
    "point_layout",
]

I_BODY_A = 0
I_BODY_B = 1
I_PIECE_A = 2
I_PIECE_B = 3
I_COUNT = 4  # points in the manifold
I_ID0 = 5  # the points' feature ids: I_ID0 + j
#: bit of the flags: the contact was solved exactly this step (an island solved exactly)
FLAG_EXACT = 1
#: bit of the flags: its impact was taken before the soft step (an island with joints), so
#: the restitution pass leaves it alone
FLAG_STRUCK = 2


def flags_column(max_points: int) -> int:
    """The column of the flags in rows of manifolds of up to ``max_points`` points."""
    return I_ID0 + max_points


class PointLayout(NamedTuple):
    """The first float column, from a point's offset in its contact row, of each of its
    values in ``d`` dimensions (:func:`point_layout`)."""

    #: anchor on A, d columns [m]
    ra: int
    #: anchor on B, d columns [m]
    rb: int
    #: the separation less the anchors' part along n at the step's start [m]
    base: int
    #: effective mass along n [kg]
    nmass: int
    #: accumulated normal impulse [N s]
    jn: int
    #: accumulated tangent impulses, d - 1 columns [N s]
    jt: int
    #: normal impulse applied over the step [N s]
    total: int
    #: normal relative speed at the step's start [m/s] (negative: approaching)
    vrel: int
    #: separation at the step's start [m]
    sep: int
    #: the point, d columns [m]
    at: int
    #: the columns these take; a dimension may add its own after them
    size: int


def point_layout(d: int) -> PointLayout:
    """Where a contact point's values lie in a row of ``d``-dimensional contacts, the same
    order in 2D and 3D: the anchors, base, normal mass, impulses, total, speed, separation,
    and the point."""
    return PointLayout(
        ra=0, rb=d, base=2 * d, nmass=2 * d + 1, jn=2 * d + 2, jt=2 * d + 3, total=3 * d + 2,
        vrel=3 * d + 3, sep=3 * d + 4, at=3 * d + 5, size=4 * d + 5,
    )  # fmt: skip
