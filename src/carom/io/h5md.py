"""Trajectories in H5MD 1.1 (HDF5, through h5py): the particle-simulation format that OVITO,
MDAnalysis and VMD read.

Layout written (de Buyl et al., Comput. Phys. Commun. 185, 1546, 2014; nongnu.org/h5md)::

    /h5md                     version = [1, 1]; author, creator (carom and its version)
    /particles/all/box        dimension, boundary ("periodic" or "none" per axis), edges [m]
    /particles/all/position   step (F,) int64, time (F,) float64 [s], value (F, N, d) [m]
    /particles/all/velocity   same, value in [m s-1]
    /particles/all/orientation       same, value (F, N) [rad] in 2D (angle about z), (F, N, 4)
                              in 3D (unit quaternion w, x, y, z, body to world)
    /particles/all/angular_velocity  same, value (F, N, 3) [rad s-1] (2D: about z, column 2)
    /particles/all/shape      (N,) strings ("sphere", "box", ...)   time-independent
    /particles/all/pieces     the rigid bodies' rounded convex pieces, time-independent:
                              owner (P,) body, radius (P,) [m], corners (P,), vertices
                              (V, 2) [m] in the body's frame about its centre of mass
    /particles/all/joints     the joints (when there are any), time-independent: kind (J,)
                              strings ("revolute", ...; "removed"), bodies (J, 2) (-1: the
                              world), anchors (J, 2, d) [m] in each body's frame about its
                              centre of mass (a world point for the world)
    /particles/all/radius     (N,) [m]    time-independent
    /particles/all/mass       (N,) [kg]   (inf for static bodies)
    /observables/kinetic_energy      step, time, value (F,) [J]
    /observables/potential_energy    same (gravity; zero without it) [J]
    /observables/dissipated_energy   same: lost in collisions since the start [J]
    /observables/given_energy        same: given by the parting-speed floor (the rigid
                              engine: by its solver) since the start [J]
    /observables/work_done           same: work done by kinematic bodies since the start [J]
                              (E0 + work = kinetic + potential + dissipated - given)
    /observables/rotational_energy   same: the rotational part of the kinetic energy [J]
    /observables/angular_momentum    same, value (F, 3): about the origin, orbital plus spin
                              [kg m2 s-1] (2D: about z, column 2)

Frames are appended as the run produces them (chunked, resizable datasets). The orientation,
angular velocity, shape and pieces elements are carom's own (H5MD lets a program add elements).
"""

from __future__ import annotations

import errno
import math
import os
import shutil
import sys
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from carom import __version__
from carom.bodies import pieces_to_arrays
from carom.errors import CaromError
from carom.shape_base import SHAPE_NAMES
from carom.world import Frame, World

__all__ = [
    "BALANCE",
    "ELEMENTS",
    "ENERGIES",
    "OBSERVABLES",
    "H5MDWriter",
    "check_trajectory",
    "need_h5py",
    "read_trajectory",
    "write_failed",
]

#: the writers whose file could not be written (a full disk): HDF5 then cannot close the file,
#: its objects print errors when freed and its library crashes when the interpreter exits
#: (segfault); they are kept here, never freed, and the command line ends the process itself
#: after its message (see :func:`carom.cli.main`)
_FAILED: list[H5MDWriter] = []


def _mark_failed(writer: H5MDWriter) -> None:
    """Keep ``writer`` alive (never freed: freeing its objects makes HDF5 fail again)."""
    if writer not in _FAILED:
        _FAILED.append(writer)


def _from_h5py_dealloc(tb: TracebackType | None) -> bool:
    while tb is not None:
        if "h5py" in tb.tb_frame.f_code.co_filename and "_dealloc" in tb.tb_frame.f_code.co_name:
            return True
        tb = tb.tb_next
    return False


#: the writers open now (and those that failed), and whether the hooks below are installed
_WRITERS: list[H5MDWriter] = []
_HOOKED = False


def _quiet_h5py_dealloc(writer: H5MDWriter) -> None:
    """Once a file cannot be written, h5py prints a traceback for every HDF5 object it frees
    (hundreds: "Can't decrement id ref count"), through ``sys.excepthook`` and
    ``sys.unraisablehook``, before any write raises to carom. From the first writer on, these
    hooks drop those (the failure is reported once, by the write that raises) and mark the
    open writers failed; everything else goes to the hooks that were there before."""
    global _HOOKED
    _WRITERS.append(writer)
    if _HOOKED:
        return
    _HOOKED = True
    unraisable_hook, except_hook = sys.unraisablehook, sys.excepthook

    def dropped(tb: TracebackType | None) -> bool:
        if not _from_h5py_dealloc(tb):
            return False
        for w in _WRITERS:
            _mark_failed(w)
        return True

    def on_unraisable(unraisable: Any) -> None:
        if not dropped(unraisable.exc_traceback):
            unraisable_hook(unraisable)

    def on_exception(kind: Any, value: Any, tb: TracebackType | None) -> None:
        if not dropped(tb):
            except_hook(kind, value, tb)

    sys.unraisablehook, sys.excepthook = on_unraisable, on_exception


#: frames held in memory before they go to the file together, as one resize and one write of
#: each dataset for all of them (one frame at a time, HDF5's calls took 5 ms a frame whatever
#: its size); the writer holds at most this many bytes, and at least one frame [bytes]
BATCH_BYTES = 4 * 2**20
#: and at most this many frames
BATCH_FRAMES = 256


def frame_bytes(n: int, dim: int) -> int:
    """Bytes one frame of ``n`` bodies adds to a trajectory: position and velocity (``dim``
    each), orientation (1 in 2D, 4 in 3D) and angular velocity (3) per body, and the
    observables, all float64."""
    per_frame = sum(math.prod(shape) for shape, _ in OBSERVABLES.values())
    return 8 * (n * (2 * dim + (1 if dim == 2 else 4) + 3) + per_frame)


def write_failed() -> bool:
    """Whether a trajectory write failed in this process (HDF5 is then not safe to shut
    down: end the process with ``os._exit`` once the message is out)."""
    return bool(_FAILED)


#: free space kept on the disk beyond the next frame, for HDF5's metadata when the file is
#: closed; a run stops with a message before it goes below this (HDF5 fails, and crashes at
#: exit, when a write finds the disk full) [bytes]
DISK_MARGIN = 16 * 2**20

#: the energies written with every frame [J], each with its sign in the total that stays E0
#: (module docstring)
BALANCE = {
    "kinetic_energy": 1.0,
    "potential_energy": 1.0,
    "dissipated_energy": 1.0,
    "given_energy": -1.0,
    "work_done": -1.0,
}
ENERGIES = tuple(BALANCE)
#: every observable written with every frame: its value's shape and unit
OBSERVABLES: dict[str, tuple[tuple[int, ...], str]] = {
    **{name: ((), "J") for name in ENERGIES},
    "rotational_energy": ((), "J"),
    "angular_momentum": ((3,), "kg m2 s-1"),
}
#: the per-body elements written with every frame
ELEMENTS = ("position", "velocity", "orientation", "angular_velocity")


def need_h5py() -> Any:
    """The h5py module, or a CaromError saying how to install it."""
    try:
        import h5py  # type: ignore[import-untyped]
    except ImportError:
        raise CaromError(
            "writing the trajectory (H5MD) needs h5py: pip install 'carom[io]' "
            "(or pass --no-trajectory)"
        ) from None
    return h5py


class H5MDWriter:
    """Write a world's frames to an H5MD file as they come.

    Parameters
    ----------
    path : Path
        The file to create.
    world : World
        Gives the box, boundary, radii and masses (fixed for the run).
    """

    def __init__(self, path: Path, world: World) -> None:
        h5py = need_h5py()
        self.path = path
        self.file = h5py.File(path, "w")
        _quiet_h5py_dealloc(self)
        self.dim = world.dim
        self.n = world.n_bodies
        meta = self.file.create_group("h5md")
        meta.attrs["version"] = np.array([1, 1], dtype=np.int32)
        meta.create_group("author").attrs["name"] = "carom user"
        creator = meta.create_group("creator")
        creator.attrs["name"] = "carom"
        creator.attrs["version"] = __version__
        particles = self.file.create_group("particles/all")
        box = particles.create_group("box")
        box.attrs["dimension"] = np.int32(self.dim)
        kind = "periodic" if world.boundary == "periodic" else "none"
        box.attrs["boundary"] = np.array([kind] * self.dim, dtype=h5py.string_dtype())
        box.create_dataset("edges", data=world.box).attrs["unit"] = "m"
        radius = particles.create_dataset("radius", data=world.radii)
        radius.attrs["unit"] = "m"
        particles.create_dataset("mass", data=world.masses).attrs["unit"] = "kg"
        shapes = [SHAPE_NAMES[int(code)] for code in world.bodies.shape]
        particles.create_dataset("shape", data=np.array(shapes, dtype=h5py.string_dtype()))
        pieces = particles.create_group("pieces")
        for name, value in pieces_to_arrays(world.bodies.pieces, self.dim).items():
            pieces.create_dataset(name, data=value)
        pieces["radius"].attrs["unit"] = pieces["vertices"].attrs["unit"] = "m"
        if getattr(world, "n_joints", 0):
            _write_joints(particles.create_group("joints"), world, h5py)
        orientation = (self.n,) if self.dim == 2 else (self.n, 4)
        observables = self.file.require_group("observables")
        self.groups = {
            "position": self._element(particles, "position", (self.n, self.dim), "m"),
            "velocity": self._element(particles, "velocity", (self.n, self.dim), "m s-1"),
            "orientation": self._element(
                particles, "orientation", orientation, "rad" if self.dim == 2 else ""
            ),
            "angular_velocity": self._element(
                particles, "angular_velocity", (self.n, 3), "rad s-1"
            ),
            **{
                name: self._element(observables, name, shape, unit)
                for name, (shape, unit) in OBSERVABLES.items()
            },
        }
        self._hold_frames(0)

    @classmethod
    def reopen(cls, path: Path, world: World, frames: int) -> H5MDWriter:
        """Open a trajectory written by an interrupted run to append to it, keeping its first
        ``frames`` frames (those its checkpoint knows) and dropping any written after."""
        h5py = need_h5py()
        self = cls.__new__(cls)
        self.path = path
        try:
            self.file = h5py.File(path, "r+")
            _quiet_h5py_dealloc(self)
            self.groups = {
                **{name: self.file[f"particles/all/{name}"] for name in ELEMENTS},
                **{name: self.file[f"observables/{name}"] for name in OBSERVABLES},
            }
        except (OSError, KeyError) as exc:
            raise CaromError(
                f"cannot reopen the trajectory {path} to resume ({exc}); pass --force to start "
                f"again"
            ) from None
        self.dim, self.n = world.dim, world.n_bodies
        for group in self.groups.values():
            for dataset in ("step", "time", "value"):
                held = group[dataset].shape[0]
                if held < frames:
                    self.file.close()  # (the count was read first: a closed file reads nothing)
                    raise CaromError(
                        f"the trajectory {path} holds fewer frames than its checkpoint "
                        f"({held} < {frames}); pass --force to start again"
                    )
                group[dataset].resize(frames, axis=0)
        self._hold_frames(frames)
        return self

    @property
    def frames(self) -> int:
        """The frames written so far, those held for the next batch included."""
        return self.written + len(self.held)

    def _hold_frames(self, written: int) -> None:
        """Start holding frames; ``written`` are in the file."""
        self.written = written
        self.batch = max(1, min(BATCH_FRAMES, BATCH_BYTES // frame_bytes(self.n, self.dim)))
        self.held: list[tuple[float, list[Any]]] = []
        #: each element's and observable's row (one frame's value), as in the file
        self.rows = [self.groups[name]["value"].shape[1:] for name in (*ELEMENTS, *OBSERVABLES)]

    def flush(self) -> None:
        """Push everything written so far to the file (before a checkpoint names it)."""
        self._write_held()
        try:
            self.file.flush()
        except OSError:
            _mark_failed(self)
            raise

    @staticmethod
    def _element(parent: Any, name: str, shape: tuple[int, ...], unit: str) -> Any:
        group = parent.create_group(name)
        group.create_dataset("step", shape=(0,), maxshape=(None,), dtype=np.int64, chunks=True)
        time = group.create_dataset(
            "time", shape=(0,), maxshape=(None,), dtype=np.float64, chunks=True
        )
        time.attrs["unit"] = "s"
        value = group.create_dataset(
            "value",
            shape=(0, *shape),
            maxshape=(None, *shape),
            dtype=np.float64,
            chunks=(1, *shape) if shape else (1024,),
        )
        value.attrs["unit"] = unit
        return group

    def write(self, frame: Frame, observed: Mapping[str, Any]) -> None:
        """Append one frame and its observables, by name (every one of :data:`OBSERVABLES`).
        The frame is held, with others, until :data:`BATCH_BYTES` or :data:`BATCH_FRAMES`
        are, or :meth:`flush` or :meth:`close` is called; ``frames`` counts it at once.

        Raises
        ------
        OSError
            The disk has less than the frames held plus :data:`DISK_MARGIN` free (checked
            first, so that the file can still be closed), or the write failed.
        """
        values = [
            frame.positions,
            frame.velocities,
            frame.orientations,
            frame.angular_velocities,
            *(observed[name] for name in OBSERVABLES),
        ]
        rows = [
            np.broadcast_to(np.asarray(value, dtype=np.float64), row).copy()
            for value, row in zip(values, self.rows, strict=True)
        ]
        self.held.append((frame.time, rows))
        if len(self.held) >= self.batch:
            self._write_held()

    def _write_held(self) -> None:
        """Write the frames held: one resize and one write of each dataset for all."""
        if not self.held:
            return
        free = shutil.disk_usage(self.path.parent).free
        if free < len(self.held) * frame_bytes(self.n, self.dim) + DISK_MARGIN:
            raise OSError(
                errno.ENOSPC,
                f"{os.strerror(errno.ENOSPC)} (less than {DISK_MARGIN // 2**20} MiB free, kept "
                f"for closing the trajectory)",
                str(self.path),
            )
        k, count = self.written, len(self.held)
        steps = np.arange(k, k + count, dtype=np.int64)
        times = np.array([t for t, _ in self.held])
        try:
            for column, name in enumerate((*ELEMENTS, *OBSERVABLES)):
                group = self.groups[name]
                for dataset in ("step", "time", "value"):
                    group[dataset].resize(k + count, axis=0)
                group["step"][k:] = steps
                group["time"][k:] = times
                group["value"][k:] = np.stack([values[column] for _, values in self.held])
        except OSError:
            _mark_failed(self)
            raise
        self.written = k + count
        self.held.clear()

    def close(self) -> None:
        """Close the file; after a failed write, as far as HDF5 can (the failure was
        reported where it happened)."""
        unwritten: OSError | None = None
        if self not in _FAILED:
            try:
                self._write_held()
            except OSError as error:  # (the file is closed first all the same)
                unwritten = error
        try:
            self.file.close()
        except OSError:
            if not _FAILED:
                _mark_failed(self)
                raise
        if self not in _FAILED and self in _WRITERS:
            _WRITERS.remove(self)
        if unwritten is not None:
            raise unwritten

    def __enter__(self) -> H5MDWriter:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()


def _write_joints(group: Any, world: World, h5py: Any) -> None:
    """The world's joints into ``group`` (the module docstring's layout)."""
    from carom.engines.rigid import joints as rows2
    from carom.engines.rigid3d import joints as rows3
    from carom.engines.stepped import joints as shared

    ints, floats = world.joint_rows
    names = [
        "removed" if k == shared.REMOVED else shared.KIND_NAMES[int(k)]
        for k in ints[:, shared.J_KIND]
    ]
    group.create_dataset("kind", data=np.array(names, dtype=h5py.string_dtype()))
    group.create_dataset("bodies", data=ints[:, [shared.J_A, shared.J_B]])
    if world.dim == 2:
        anchors = floats[:, rows2.LAX : rows2.LBY + 1].reshape(-1, 2, 2)
    else:
        anchors = floats[:, rows3.LA : rows3.LB + 3].reshape(-1, 2, 3)
    group.create_dataset("anchors", data=anchors).attrs["unit"] = "m"


@contextmanager
def read_trajectory(path: Path) -> Iterator[Any]:
    """Open a trajectory to read; a file that is damaged or not carom's (not HDF5, or without
    the H5MD groups carom writes) is a :class:`CaromError` naming it, not an h5py traceback.

    Yields
    ------
    h5py.File
        Open read-only; closed when the block ends.
    """
    h5py = need_h5py()
    try:
        handle = h5py.File(path, "r")
    except OSError as exc:
        raise CaromError(
            f"{path} is not a readable trajectory ({exc}); it is damaged or was not written by "
            f"carom: run the scene again"
        ) from None
    with handle:
        try:
            yield handle
        except KeyError as exc:
            raise CaromError(
                f"{path} lacks part of a carom trajectory ({exc}); it is damaged or was not "
                f"written by carom: run the scene again"
            ) from None


def check_trajectory(path: Path, world: World, frames: int) -> None:
    """Read ``path`` back and check it holds ``frames`` frames of ``world``'s bodies, the last
    one equal to the world now; a CaromError if not (nothing half-written is kept)."""
    h5py = need_h5py()
    with h5py.File(path, "r") as f:
        now = world.frame()
        last = {name: f[f"particles/all/{name}/value"] for name in ELEMENTS}
        ok = (
            tuple(f["h5md"].attrs["version"]) == (1, 1)
            and all(d.shape[0] == frames for d in last.values())
            and f["particles/all/position/time"][-1] == world.time
            and np.array_equal(last["position"][-1], now.positions)
            and np.array_equal(last["velocity"][-1], now.velocities)
            and np.array_equal(last["orientation"][-1], now.orientations)
            and np.array_equal(last["angular_velocity"][-1], now.angular_velocities)
        )
    if not ok:
        raise CaromError(f"the trajectory written to {path} does not read back as written")
