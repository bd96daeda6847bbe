"""Interactive replays in the rerun viewer (the ``view`` extra: ``pip install 'carom[view]'``).

:func:`write_recording` turns the H5MD trajectory that ``carom run`` wrote into a rerun
recording (``.rrd``): the box, every sphere (a disk in 2D) coloured by speed, every 2D rigid
body of another shape as its outline turned by its angle (a circle with a spoke, so that its
turning shows), coloured alike (static bodies grey), every 3D rigid body as a shaded mesh of
its pieces' faces (logged once, then moved and turned frame by frame; static and kinematic
bodies translucent grey), velocities as arrows, and the energies
(translational and rotational kinetic apart) and the angular momentum against time, all on
two timelines, ``frame`` (the frame number) and ``time`` (simulated seconds). The viewer's
timeline scrubs, plays and loops it.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np

from carom.errors import CaromError

__all__ = ["RECORDING", "can_show", "need_rerun", "open_viewer", "write_recording"]

RECORDING = "recording.rrd"
#: entity paths in the recording
BOX, BODIES, SHAPES, VELOCITIES = "world/box", "world/bodies", "world/shapes", "world/velocities"
#: each 3D rigid body's mesh is logged under this path, then its number
MESHES = "world/meshes"
#: colours of the 3D rigid bodies' meshes (RGBA), dynamic ones in turn; the still ones grey
MESH_COLOURS = np.array(
    [[76, 114, 176, 255], [221, 132, 82, 255], [85, 168, 104, 255], [196, 78, 82, 255],
     [129, 114, 179, 255], [147, 120, 96, 255], [218, 139, 195, 255], [204, 185, 116, 255]],
    np.uint8,
)  # fmt: skip
STILL_COLOUR = np.array([150, 150, 150, 90], np.uint8)
ENERGY, ANGULAR_MOMENTUM = "energy", "angular_momentum"


def need_rerun() -> Any:
    """The rerun module, or a CaromError saying how to install it."""
    try:
        import rerun as rr
    except ImportError:
        raise CaromError(
            "carom view needs the rerun viewer's SDK: install the view extra, "
            "pip install 'carom[view]'"
        ) from None
    return rr


def write_recording(folder: Path, out: Path | None = None) -> Path:
    """Write ``folder/recording.rrd`` (or ``out``) from ``folder/trajectory.h5``.

    Parameters
    ----------
    folder : Path
        A ``carom run`` output directory holding ``trajectory.h5``.
    out : Path, optional
        Where to write the recording; ``folder / "recording.rrd"`` by default. It is written
        beside it first and renamed, so an existing recording is replaced whole or not at all.

    Returns
    -------
    Path
        The recording.

    Raises
    ------
    CaromError
        No trajectory in ``folder``, or rerun (or h5py) missing.
    """
    from carom.io.h5md import read_trajectory

    trajectory = folder / "trajectory.h5"
    if not trajectory.is_file():
        raise CaromError(
            f"{folder} holds no trajectory.h5 to replay; run 'carom run SCENE --out {folder}' "
            f"first (without --no-trajectory)"
        )
    rr = need_rerun()
    out = out or folder / RECORDING
    partial = out.with_name(out.name + ".partial")
    stream = rr.RecordingStream("carom", recording_id=f"carom:{folder.resolve().name}")
    stream.save(partial)
    try:
        with read_trajectory(trajectory) as f:
            _log_all(rr, stream, f)
        stream.flush()
        stream.disconnect()
    except BaseException:
        partial.unlink(missing_ok=True)
        raise
    partial.replace(out)
    return out


def _log_all(rr: Any, stream: Any, f: Any) -> None:
    from carom.io.h5md import BALANCE
    from carom.viz.animate import (
        TrajectoryScene,
        placed_strips,
        sampled_speeds,
        speed_colours,
        speed_scale,
    )

    scene = TrajectoryScene.read(f)
    box, radius, moving, round_ = scene.box, scene.radius, scene.moving, scene.round
    times = f["particles/all/position/time"][:]
    positions = f["particles/all/position/value"]
    velocities = f["particles/all/velocity/value"]
    angles = f["particles/all/orientation/value"]
    Points = rr.Points3D if scene.dim == 3 else rr.Points2D
    Arrows = rr.Arrows3D if scene.dim == 3 else rr.Arrows2D
    if scene.dim == 3:
        stream.log(BOX, rr.Boxes3D(centers=[box / 2], half_sizes=[box / 2]), static=True)
    else:
        stream.log(BOX, rr.Boxes2D(mins=[[0.0, 0.0]], sizes=[box]), static=True)
    # colours as in the film; arrows: a typical speed (the 90th percentile) draws two radii
    speeds = sampled_speeds(velocities, moving)
    top = speed_scale(speeds)
    typical = float(np.percentile(speeds, 90)) if speeds.size else 0.0
    arrow_time = 2.0 * float(np.median(radius)) / typical if typical > 0 else 0.0
    # the rigid bodies' outlines (2D), one strip per piece, coloured by their body
    outlines = scene.outlines
    strips = outlines.strips() if scene.dim == 2 and len(outlines.body) else None
    observed = f["observables"]
    series = {name: observed[f"{name}/value"][:] for name in BALANCE}
    rotational = observed["rotational_energy/value"][:]
    spins = bool(np.any(rotational))  # translational and rotational apart only then
    spin = observed["angular_momentum/value"][:]
    axes = range(3) if scene.dim == 3 else (2,)
    spheres = bool(np.any(round_))
    if scene.dim == 3 and len(scene.facets.body):
        _log_meshes(rr, stream, scene, times, positions[:], np.asarray(angles[:], float))
    for k in range(len(times)):
        stream.set_time("frame", sequence=k)
        stream.set_time("time", duration=float(times[k]))
        x, v = positions[k], velocities[k]
        colours = (speed_colours(v, moving, top) * 255).astype(np.uint8)
        if spheres:
            stream.log(BODIES, Points(x[round_], radii=radius[round_], colors=colours[round_]))
        if strips is not None:
            placed = placed_strips(strips, x, np.asarray(angles[k], float))
            stream.log(SHAPES, rr.LineStrips2D(placed, colors=colours[outlines.body]))
        stream.log(VELOCITIES, Arrows(origins=x[moving], vectors=v[moving] * arrow_time))
        total = 0.0
        for name, values in series.items():
            total += BALANCE[name] * float(values[k])
            if name == "kinetic_energy" and spins:
                stream.log(f"{ENERGY}/translational", rr.Scalars(float(values[k] - rotational[k])))
                stream.log(f"{ENERGY}/rotational", rr.Scalars(float(rotational[k])))
            stream.log(f"{ENERGY}/{name.removesuffix('_energy')}", rr.Scalars(float(values[k])))
        stream.log(f"{ENERGY}/total", rr.Scalars(total))
        for axis in axes:
            value = float(spin[k, axis])
            stream.log(f"{ANGULAR_MOMENTUM}/{'xyz'[axis]}", rr.Scalars(value))


def _log_meshes(rr: Any, stream: Any, scene: Any, times: Any, x: Any, q: Any) -> None:
    """Each 3D rigid body's faces as one flat-shaded mesh in its frame, logged once, and its
    pose (translation and quaternion) on both timelines, all frames in one column; a body
    that never moves gets one static pose. x (frames, N, 3) [m]; q (frames, N, 4)
    ``(w, x, y, z)``."""
    facets = scene.facets
    frames = np.arange(len(times))
    dynamic = 0
    for body in np.unique(facets.body):
        triangles = facets.corners[facets.body == body]  # (t, 3, 3), body frame
        normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
        size = np.linalg.norm(normal, axis=1, keepdims=True)
        normal = np.repeat(normal / np.where(size > 0.0, size, 1.0), 3, axis=0)
        if scene.moving[body]:
            colour = MESH_COLOURS[dynamic % len(MESH_COLOURS)]
            dynamic += 1
        else:
            colour = STILL_COLOUR
        path = f"{MESHES}/{int(body)}"
        mesh = rr.Mesh3D(
            vertex_positions=triangles.reshape(-1, 3),
            triangle_indices=np.arange(3 * len(triangles), dtype=np.uint32).reshape(-1, 3),
            vertex_normals=normal,
            albedo_factor=colour,
        )
        where = np.asarray(x[:, body], float)
        turn = q[:, body][:, [1, 2, 3, 0]]  # rerun's order: (x, y, z, w)
        if np.all(where == where[0]) and np.all(turn == turn[0]):
            pose = rr.Transform3D(translation=where[0], quaternion=rr.Quaternion(xyzw=turn[0]))
            stream.log(path, mesh, pose, static=True)
            continue
        stream.log(path, mesh, static=True)
        stream.send_columns(
            path,
            indexes=[
                rr.TimeColumn("frame", sequence=frames),
                rr.TimeColumn("time", duration=np.asarray(times, float)),
            ],
            columns=rr.Transform3D.columns(translation=where, quaternion=turn),
        )


def can_show() -> bool:
    """Whether a viewer window can open here: a desktop, and not a CI machine."""
    if os.environ.get("CI"):
        return False
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def open_viewer(recording: Path) -> None:
    """Start the rerun viewer on ``recording`` in the background."""
    viewer = shutil.which("rerun")
    command = [viewer] if viewer else [sys.executable, "-m", "rerun"]
    subprocess.Popen(
        [*command, str(recording)],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
