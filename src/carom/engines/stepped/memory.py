"""What a stepped engine keeps from step to step beside its bodies' motion, the same in 2D and
3D: which bodies sleep and for how long they have been still (Box2D's islands and sleep), and
the last step's contact impulses, which warm-start the next (Box2D's and Rapier's warm start).

A world builds its engine again when it changes between steps (a body added, a kind switched,
gravity or a material set). The engine built in its place takes this memory over
(:func:`carried`), so that a change does not disturb what it leaves alone: the warm starts of
every contact whose two pieces are still there, and the sleep of every body that is still
there, unchanged, under unchanged laws. Without it, a ball shot into a game's world woke every
sleeping stack in it and let each settle again from cold impulses.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from carom.engines.base import Partners
from carom.laws.kinds import KIND_DYNAMIC

__all__ = [
    "Laws",
    "Remembered",
    "Renumbering",
    "StepMemory",
    "carried",
    "new_memory",
    "rekeyed",
    "remembered",
    "renumbering",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


class StepMemory(NamedTuple):
    """Sleep and the warm-start cache of N bodies (a checkpoint keeps them by these names).

    Attributes
    ----------
    awake : (N,) bool
        Dynamic bodies being simulated (false: asleep).
    clock : (N,) float64
        How long each body has been slow enough to sleep [s].
    island : (N,) int64
        The island a sleeping body sleeps in (its root body).
    cache_keys : (K,) int64
        Contacts of the last step (``a * P + b`` for pieces ``a < b`` of P), sorted.
    cache_ids : (K, points) int64
        Their points' feature ids (-1: no point).
    cache_impulses : float64
        Each point's normal impulse and its tangent impulse [N s]: (K, 4) in 2D (normal and
        tangent of each of two points), (K, 4, 4) in 3D (the tangent as a world vector).
    cache_count : (1,) int64
        How many rows of the cache are used.
    """

    awake: NDArray[np.bool_]
    clock: FloatArray
    island: IntArray
    cache_keys: IntArray
    cache_ids: IntArray
    cache_impulses: FloatArray
    cache_count: IntArray


def new_memory(kind: NDArray[np.int8], points: int, impulse_shape: tuple[int, ...]) -> StepMemory:
    """The memory at the start: every dynamic body awake, no contact cached; a cached
    contact has up to ``points`` points and impulses of ``impulse_shape`` per row."""
    n = kind.shape[0]
    return StepMemory(
        awake=kind == KIND_DYNAMIC,
        clock=np.zeros(n),
        island=np.arange(n, dtype=np.int64),
        cache_keys=np.zeros(0, np.int64),
        cache_ids=np.zeros((0, points), np.int64),
        cache_impulses=np.zeros((0, *impulse_shape)),
        cache_count=np.zeros(1, np.int64),
    )


class Laws(NamedTuple):
    """What an engine's sleep depends on besides its bodies' motion.

    Attributes
    ----------
    gravity : (d,) float64
        [m/s^2].
    settings : object
        The engine's settings (a frozen dataclass: compared by value).
    tables : tuple of (M, M) float64
        Its contact tables over the M materials (restitution, friction, ...).
    """

    gravity: FloatArray
    settings: Any
    tables: tuple[FloatArray, ...]


class Remembered(NamedTuple):
    """What a running engine hands the engine built in its place (:func:`carried`).

    Attributes
    ----------
    memory : StepMemory
        Its memory (the cache's used rows only; copies).
    partners : Partners
        Whom each of its N bodies stands for: a caller's body, a wall or a plane.
    body_pieces : (N + 1,) int64
        Where each body's pieces start (the model's).
    kind, material : (N,) int64
        Each body's kind and the row of its material in the tables.
    motion : tuple of arrays
        Its caller's bodies' motion (:meth:`sample`): positions (n, d) [m], velocities
        (n, d) [m/s], orientations, angular velocities (n, 3) [rad/s].
    laws : Laws
        Gravity, the settings and the contact tables: sleep is carried only when they act
        on the bodies carried as they did.
    keyed : tuple of arrays
        The dimension's own rows keyed by piece pairs, used rows only (copies): the keys
        (K,) then each table's rows (K, ...); in 3D the manifolds kept from step to step.
    """

    memory: StepMemory
    partners: Partners
    body_pieces: IntArray
    kind: IntArray
    material: IntArray
    motion: tuple[FloatArray, ...]
    laws: Laws
    keyed: tuple[NDArray[Any], ...]


def remembered(
    memory: StepMemory,
    partners: Partners,
    body_pieces: IntArray,
    kind: IntArray,
    material: IntArray,
    motion: tuple[FloatArray, ...],
    laws: Laws,
    keyed: tuple[NDArray[Any], ...] = (),
) -> Remembered:
    """A running engine's :class:`Remembered`: its arrays copied, so that the engine may go on
    (a change refused) without touching them."""
    used = int(memory.cache_count[0])
    kept = StepMemory(
        memory.awake.copy(),
        memory.clock.copy(),
        memory.island.copy(),
        memory.cache_keys[:used].copy(),
        memory.cache_ids[:used].copy(),
        memory.cache_impulses[:used].copy(),
        memory.cache_count.copy(),
    )
    return Remembered(
        kept, partners, body_pieces.copy(), kind.copy(), material.copy(), motion, laws,
        tuple(each.copy() for each in keyed),
    )  # fmt: skip


def _same_laws(kept: Remembered, to_new: IntArray, material: IntArray, laws: Laws) -> bool:
    """Whether the laws act on the bodies carried over as they did: the same gravity and
    settings, and the same table entries between their materials (a material added for a
    new body changes nothing for the others)."""
    before = kept.laws
    if not np.array_equal(before.gravity, laws.gravity) or before.settings != laws.settings:
        return False
    there = to_new >= 0
    pairs = np.unique(np.stack([kept.material[there], material[to_new[there]]]), axis=1)
    if len(np.unique(pairs[0])) != pairs.shape[1]:
        return False  # (one material became two)
    was, now = np.ix_(pairs[0], pairs[0]), np.ix_(pairs[1], pairs[1])
    return len(before.tables) == len(laws.tables) and all(
        np.array_equal(a[was], b[now]) for a, b in zip(before.tables, laws.tables, strict=True)
    )


def _body_map(old: Partners, new: Partners) -> IntArray:
    """Each old body's row in the new engine (-1: gone), matched by whom it stands for."""
    width = max(int(old.number.max(initial=0)), int(new.number.max(initial=0))) + 1
    old_code = old.kind.astype(np.int64) * width + old.number
    new_code = new.kind.astype(np.int64) * width + new.number
    order = np.argsort(new_code, kind="stable")
    codes = new_code[order]
    at = np.searchsorted(codes, old_code)
    hit = at < len(codes)
    hit[hit] = codes[at[hit]] == old_code[hit]
    out = np.full(len(old_code), -1, np.int64)
    out[hit] = order[at[hit]]
    return out


class Renumbering(NamedTuple):
    """Where an old engine's bodies and pieces are in the engine built in its place.

    Attributes
    ----------
    bodies : (N_old,) int64
        Each old body's row now (-1: gone).
    same : (N_old,) bool
        The old bodies that are there with the same pieces.
    pieces : (P_old,) int64
        Each old piece's row now (-1: its body gone or its pieces changed).
    old_pieces, new_pieces : int
        P_old and P, which contact keys ``a * P + b`` are made with.
    """

    bodies: IntArray
    same: NDArray[np.bool_]
    pieces: IntArray
    old_pieces: int
    new_pieces: int


def renumbering(kept: Remembered, partners: Partners, body_pieces: IntArray) -> Renumbering:
    """How ``kept``'s bodies and pieces map onto an engine of ``partners`` whose bodies'
    pieces start at ``body_pieces`` (N + 1,): a body by whom it stands for (the caller's
    body, a wall, a plane), its k-th piece to its k-th piece if it has as many."""
    to_new = _body_map(kept.partners, partners)
    old_count = np.diff(kept.body_pieces)
    same = to_new >= 0
    same[same] = old_count[same] == np.diff(body_pieces)[to_new[same]]
    old_pieces = int(kept.body_pieces[-1])
    owner = np.repeat(np.arange(len(old_count)), old_count)
    pieces = np.full(old_pieces, -1, np.int64)
    moved = same[owner]
    first_now = body_pieces[to_new[owner[moved]]]
    pieces[moved] = first_now + np.flatnonzero(moved) - kept.body_pieces[owner[moved]]
    return Renumbering(to_new, same, pieces, old_pieces, int(body_pieces[-1]))


def rekeyed(where: Renumbering, keys: IntArray) -> tuple[IntArray, IntArray]:
    """The rows of a table keyed by piece pairs (``keys``, ``a * P_old + b``, a < b) whose
    two pieces are still there, in the order of their new keys, and those keys (sorted):
    a row's contents (feature ids, impulses, a manifold's points) hold as they were, since
    a < b stays a < b."""
    a, b = np.divmod(keys, where.old_pieces)
    na, nb = where.pieces[a], where.pieces[b]
    keep = (na >= 0) & (nb >= 0) & (na < nb)
    new = na[keep] * where.new_pieces + nb[keep]
    order = np.argsort(new, kind="stable")
    return np.flatnonzero(keep)[order], new[order]


def carried(
    kept: Remembered,
    where: Renumbering,
    kind: IntArray,
    material: IntArray,
    motion: tuple[FloatArray, ...],
    laws: Laws,
    fresh: StepMemory,
) -> StepMemory:
    """The memory of an engine built in place of the one that handed over ``kept``, onto
    which ``where`` maps its bodies and pieces (:func:`renumbering`), whose own bodies are
    described by ``kind``, ``material``, ``motion`` and ``laws`` as in :class:`Remembered`,
    and whose memory at the start is ``fresh``.

    - A contact is warm-started as before when its two bodies are still there with the same
      pieces: its key is renumbered, its feature ids and impulses kept.
    - A body sleeps on, with its island and sleep clock, when the laws are the same and it is
      dynamic in both, with the same pieces and exactly the same motion; any other body
      starts awake (and wakes the islands it touches at the next step, as a pushed body does).
    """
    old = kept.memory
    to_new, same = where.bodies, where.same
    cached, keys = rekeyed(where, old.cache_keys[: int(old.cache_count[0])])
    size = max(len(cached), fresh.cache_keys.shape[0])
    cache_keys = np.zeros(size, np.int64)
    cache_ids = np.full((size, *old.cache_ids.shape[1:]), -1, np.int64)
    cache_impulses = np.zeros((size, *old.cache_impulses.shape[1:]))
    cache_keys[: len(cached)] = keys
    cache_ids[: len(cached)] = old.cache_ids[cached]
    cache_impulses[: len(cached)] = old.cache_impulses[cached]
    awake, clock, island = fresh.awake.copy(), fresh.clock.copy(), fresh.island.copy()
    if _same_laws(kept, to_new, material, laws):
        bodies = np.flatnonzero(same[: kept.motion[0].shape[0]])  # the caller's, kept
        rows = to_new[bodies]
        callers = rows < motion[0].shape[0]
        bodies, rows = bodies[callers], rows[callers]
        still = (kept.kind[bodies] == KIND_DYNAMIC) & (kind[rows] == KIND_DYNAMIC)
        for before, now in zip(kept.motion, motion, strict=True):
            width = int(np.prod(before.shape[1:]))
            still &= np.all(
                before[bodies].reshape(-1, width) == now[rows].reshape(-1, width), axis=1
            )
        bodies, rows = bodies[still], rows[still]
        # a body sleeps on in its island when the island's root sleeps on too; one that
        # slept and does not starts awake, its clock at 0, as a woken body does
        asleep = np.zeros(len(awake), np.bool_)
        asleep[rows] = ~old.awake[bodies]
        root = np.full(len(awake), -1, np.int64)
        root[rows] = to_new[old.island[bodies]]
        asleep[rows] &= root[rows] >= 0
        asleep[rows] &= asleep[np.maximum(root[rows], 0)]
        on = asleep[rows] | old.awake[bodies]
        clock[rows[on]] = old.clock[bodies[on]]
        sleepers = rows[asleep[rows]]
        awake[sleepers] = False
        island[sleepers] = root[sleepers]
    return StepMemory(
        awake, clock, island, cache_keys, cache_ids, cache_impulses,
        np.array([len(cached)], np.int64),
    )  # fmt: skip
