"""Joints in the rigid engines: what both dimensions share (issue 43).

A joint is one row of two arrays, as a contact is: integers (:data:`J_KIND`, the two bodies
:data:`J_A` and :data:`J_B`, :data:`J_FLAGS`) and floats (the local anchors and axes, the
limits, motor and spring, the impulses it accumulated, its reaction; each dimension lays its
own out: :mod:`carom.engines.rigid.joints`, :mod:`carom.engines.rigid3d.joints`). A body
``-1`` is the world: a fixed frame at the origin, so its "local" anchor is a world point.

Joints are solved in the soft step beside the contacts (Box2D v3's order: warm start, solve
with the soft bias, relax without it, joints before contacts each time). What a step asks of
them here: the bodies they join (:func:`links`), which join islands and keep them in the
solver (a joined body does not fly free nor take the exact path, whose bodies move in free
flight between impacts), and the pairs of bodies they keep from touching
(:func:`joined_keys`; Box2D's ``collideConnected``, false by default).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from carom.engines.stepped.solver import softness

__all__ = [
    "DISTANCE",
    "FLAG_COLLIDE",
    "FLAG_LIMIT",
    "FLAG_MOTOR",
    "FLAG_SPRING",
    "JOINT_DAMPING_RATIO",
    "JOINT_INTS",
    "J_A",
    "J_B",
    "J_FLAGS",
    "J_KIND",
    "KIND_NAMES",
    "PRISMATIC",
    "REMOVED",
    "REVOLUTE",
    "SPHERICAL",
    "TARGET",
    "WELD",
    "WHEEL",
    "joined",
    "joined_keys",
    "joint_softness",
    "joints_now",
    "links",
    "rod_rows",
]

#: the kinds of joint (a removed joint keeps its row as REMOVED: the others keep their index)
REMOVED, REVOLUTE, PRISMATIC, DISTANCE, WELD, WHEEL, TARGET, SPHERICAL = -1, 0, 1, 2, 3, 4, 5, 6
#: their names, by kind
KIND_NAMES = ("revolute", "prismatic", "distance", "weld", "wheel", "target", "spherical")
#: the integer columns of a joint row
J_KIND, J_A, J_B, J_FLAGS = 0, 1, 2, 3
JOINT_INTS = 4
#: the bits of J_FLAGS: limits on, motor on, spring on, the two bodies may touch
FLAG_LIMIT, FLAG_MOTOR, FLAG_SPRING, FLAG_COLLIDE = 1, 2, 4, 8


def links(ji: np.ndarray) -> np.ndarray:
    """The bodies (L, 2) int64 of the joints in ``ji`` (J, JOINT_INTS), removed ones left
    out; -1 for the world."""
    live = ji[:, J_KIND] != REMOVED
    return np.ascontiguousarray(ji[live][:, [J_A, J_B]], dtype=np.int64)


def joined_keys(ji: np.ndarray, n: int) -> np.ndarray:
    """The pairs of bodies that joints keep from touching, as sorted keys ``a * n + b``
    (a < b) (K,) int64 for :func:`carom.engines.stepped.filters.filter_pairs`: the live joints
    between two bodies without :data:`FLAG_COLLIDE`."""
    keep = (ji[:, J_KIND] != REMOVED) & (ji[:, J_FLAGS] & FLAG_COLLIDE == 0)
    keep &= (ji[:, J_A] >= 0) & (ji[:, J_B] >= 0)
    a = np.minimum(ji[keep, J_A], ji[keep, J_B])
    b = np.maximum(ji[keep, J_A], ji[keep, J_B])
    return np.unique(a * n + b).astype(np.int64)


@njit(cache=True, inline="always")
def joined(keys: np.ndarray, a: int, b: int, n: int) -> bool:
    """Whether bodies ``a`` and ``b`` are a pair of ``keys`` (:func:`joined_keys`)."""
    if keys.shape[0] == 0:
        return False
    key = min(a, b) * n + max(a, b)
    k = np.searchsorted(keys, key)
    return bool(k < keys.shape[0] and keys[k] == key)


#: a joint's rigid constraints are this many times as stiff as a contact in the pass with
#: the bias
JOINT_HERTZ_SCALE = 2.0
#: the damping ratio of a joint's rigid constraints in the pass with the bias (Box2D v3's
#: ``jointDampingRatio``)
JOINT_DAMPING_RATIO = 2.0


@njit(cache=True)
def joint_softness(h: float, contact_hertz: float) -> tuple[float, float, float]:
    """The softness (rate [1/s], mass scale, impulse scale) of a joint's rigid constraints
    over substep ``h`` [s]: twice as stiff as a contact (as Box2D v3's joints), no stiffer
    than half the substep rate, at :data:`JOINT_DAMPING_RATIO`."""
    hertz = min(JOINT_HERTZ_SCALE * contact_hertz, 0.5 / h)
    return softness(hertz, JOINT_DAMPING_RATIO, h)


@njit(cache=True)
def joints_now(
    ji: np.ndarray, role: np.ndarray, solver_role: int, dynamic: np.ndarray, parent: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The joints the soft step solves this step, and the bodies of their islands.

    Parameters
    ----------
    ji : (J, 4) int64
        The joints' integer rows (removed ones have kind :data:`REMOVED`).
    role : (N,) int64
        Each body's role this step (:mod:`carom.engines.stepped.islands`); the solver's is
        ``solver_role``.
    dynamic : (N,) bool
        The dynamic bodies.
    parent : (N,) int64
        Each body's island root.

    Returns
    -------
    active : (A,) int64
        The live joints with a dynamic body the solver solves, ascending.
    jointed : (N,) bool
        The dynamic bodies whose island holds one of them (their contacts take their
        impacts first).
    """
    n = role.shape[0]
    jointed = np.zeros(n, np.bool_)
    active = np.empty(ji.shape[0], np.int64)
    count = 0
    rooted = np.zeros(n, np.bool_)
    for j in range(ji.shape[0]):
        if ji[j, J_KIND] == REMOVED:
            continue
        a, b = ji[j, J_A], ji[j, J_B]
        solved = (a >= 0 and role[a] == solver_role and dynamic[a]) or (
            b >= 0 and role[b] == solver_role and dynamic[b]
        )
        if not solved:
            continue
        active[count] = j
        count += 1
        for body in (a, b):
            if body >= 0:
                rooted[parent[body]] = True
    if count:
        for i in range(n):
            jointed[i] = dynamic[i] and rooted[parent[i]]
    return active[:count], jointed


def rod_rows(
    body: int, anchor: tuple[float, ...], length: float, rows: Any
) -> tuple[np.ndarray, np.ndarray]:
    """The rows (1, 4) and (1, F) of a rigid distance joint holding ``body``'s centre
    ``length`` [m] from the world point ``anchor`` [m], in a dimension's layout ``rows`` (the
    module of :mod:`carom.engines.rigid.joints` or :mod:`carom.engines.rigid3d.joints`): the
    engines' warm-ups use it to load the joints' kernels."""
    ints = np.array([[DISTANCE, -1, body, 0]], np.int64)
    floats = np.zeros((1, int(rows.JOINT_FLOATS)))
    la = int(rows.LA)
    floats[0, la : la + len(anchor)] = anchor
    for column in ("LENGTH", "LOWER", "UPPER"):
        floats[0, int(getattr(rows, column))] = length
    return ints, floats
