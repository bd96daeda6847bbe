"""`carom view`: the rerun recording of a run, read back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.cli.helpers import carom

h5py = pytest.importorskip("h5py", reason="the io extra (h5py) is not installed")
pytest.importorskip("rerun", reason="the view extra (rerun-sdk) is not installed")


def _read(recording: Path) -> dict[str, dict[int, dict[str, np.ndarray]]]:
    """entity -> frame -> component -> values, from the .rrd file."""
    from rerun.chunk import RrdReader

    entities: dict[str, dict[int, dict[str, np.ndarray]]] = {}
    for chunk in RrdReader(recording).store().stream():
        batch = chunk.to_record_batch()
        names = batch.schema.names
        frames = batch.column("frame").to_pylist() if "frame" in names else [-1] * batch.num_rows
        for row, frame in enumerate(frames):
            values = {}
            for name in names:
                if ":" in name:
                    values[name.split(":", 1)[1]] = np.array(batch.column(name)[row].as_py())
            entities.setdefault(str(chunk.entity_path), {})[frame] = values
    return entities


def _replayed(tmp_path: Path, scene: str, until: str) -> tuple[Path, dict]:
    """Run ``scene`` to ``until`` into tmp_path/run, then ``carom view`` it with no display;
    the output folder and the recording read back."""
    out = tmp_path / "run"
    done = carom("run", scene, "--out", out, "--until", until, "--animation", "none")
    assert done.returncode == 0, done.stderr
    done = carom("view", out, CI="true")
    assert done.returncode == 0, done.stderr
    # CI has no display: the recording is written and its path said
    assert f"wrote {out / 'recording.rrd'} (no display here)" in done.stdout
    return out, _read(out / "recording.rrd")


@pytest.mark.parametrize(("scene", "dim"), [("newtons-cradle", 2), ("rain-3d", 3)])
def test_the_recording_holds_the_run(tmp_path: Path, scene: str, dim: int) -> None:
    out, data = _replayed(tmp_path, scene, "0.6")
    with h5py.File(out / "trajectory.h5", "r") as f:
        x = f["particles/all/position/value"][()]
        v = f["particles/all/velocity/value"][()]
        ke = f["observables/kinetic_energy/value"][()]
        radius = f["particles/all/radius"][()]
        box = f["particles/all/box/edges"][()]
    frames = x.shape[0]
    assert {"/world/box", "/world/bodies", "/world/velocities", "/energy/kinetic"} <= set(data)
    bodies = data["/world/bodies"]
    assert sorted(bodies) == list(range(frames))  # every frame, once
    for k in (0, frames // 2, frames - 1):
        # positions and radii as in the trajectory (rerun stores float32)
        np.testing.assert_allclose(np.stack(bodies[k]["positions"]), x[k], rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(bodies[k]["radii"], radius, rtol=1e-6)
        # arrows start at the moving bodies and point along their velocities
        arrows = data["/world/velocities"][k]
        vectors = np.stack(arrows["vectors"])
        moving = np.linalg.norm(v[k], axis=1) > 0
        cosine = np.sum(vectors[moving] * v[k][moving], axis=1) / (
            np.linalg.norm(vectors[moving], axis=1) * np.linalg.norm(v[k][moving], axis=1)
        )
        # the arrows are float32 (6e-8 relative per component, so turned by ~1e-7 rad at most
        # and their cosine is 1 to ~1e-14); 1e-5 is loose but fails any arrow turned by more
        # than sqrt(2e-5) = 0.26 degrees
        np.testing.assert_allclose(cosine, 1.0, rtol=0, atol=1e-5)
        # rerun keeps scalars as float64: the energy is the trajectory's to round-off
        assert data["/energy/kinetic"][k]["scalars"] == pytest.approx(ke[k], rel=1e-12, abs=0)
    half = data["/world/box"][-1]["half_sizes"]
    # float32 again: half an ulp is 6e-8 relative, 1e-6 covers it
    np.testing.assert_allclose(np.ravel(half), box / 2, rtol=1e-6)


def test_view_needs_a_run(tmp_path: Path) -> None:
    done = carom("view", tmp_path / "nothing", CI="true")
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert "is not a directory; give the --out DIR of a 'carom run'" in done.stderr
    done = carom("view", tmp_path, CI="true")
    assert done.returncode == 2
    assert "holds no trajectory.h5 to replay; run 'carom run SCENE --out" in done.stderr
    assert not (tmp_path / "recording.rrd").exists()


def test_rigid_bodies_are_replayed_as_their_turned_outlines(tmp_path: Path) -> None:
    # rod-drop: a 1 m x 5 cm rod (mass 1 kg) falls at 30 degrees onto a static floor slab and
    # turns on landing: every frame's rod outline must be its four corners (+-0.5, +-0.025) m
    # about its centre, turned by the trajectory's angle, closed back to the first.
    out, data = _replayed(tmp_path, "rod-drop", "0.6")
    with h5py.File(out / "trajectory.h5", "r") as f:
        x = f["particles/all/position/value"][()]
        v = f["particles/all/velocity/value"][()]
        angle = f["particles/all/orientation/value"][()]
        w = f["particles/all/angular_velocity/value"][()]
        mass = f["particles/all/mass"][()]
    rod = int(np.flatnonzero(np.isfinite(mass))[0])
    assert {"/world/shapes", "/energy/rotational", "/angular_momentum/z"} <= set(data)
    assert "/world/bodies" not in data  # no spheres here
    corners = np.array([[-0.5, -0.025], [0.5, -0.025], [0.5, 0.025], [-0.5, 0.025]])
    # I = m (w^2 + h^2) / 12 for a rectangle
    inertia = mass[rod] * (1.0 + 0.05**2) / 12.0
    turned = 0
    for k in sorted(data["/world/shapes"]):
        strip = np.array(data["/world/shapes"][k]["strips"][rod], dtype=float)
        c, s = np.cos(angle[k, rod]), np.sin(angle[k, rod])
        expected = x[k, rod] + corners @ np.array([[c, s], [-s, c]])
        assert strip.shape == (5, 2)
        np.testing.assert_array_equal(strip[0], strip[-1])  # closed
        # each corner is in the strip once; float32 in the recording: half an ulp is 6e-8
        # relative on coordinates below 4 m, so 1e-6 m covers it
        gap = np.linalg.norm(strip[:4, None, :] - expected[None, :, :], axis=2)
        assert np.all(gap.min(axis=0) < 1e-6)
        assert np.all(gap.min(axis=1) < 1e-6)
        turned += abs(angle[k, rod] - angle[0, rod]) > 1e-3
        # the scalars are float64: rotational energy I w^2 / 2, and L_z = m (x v_y - y v_x) + I w
        rot = data["/energy/rotational"][k]["scalars"]
        assert rot == pytest.approx(0.5 * inertia * w[k, rod, 2] ** 2, rel=1e-12, abs=1e-15)
        lz = mass[rod] * (x[k, rod, 0] * v[k, rod, 1] - x[k, rod, 1] * v[k, rod, 0])
        lz += inertia * w[k, rod, 2]
        assert data["/angular_momentum/z"][k]["scalars"] == pytest.approx(lz, rel=1e-12, abs=1e-15)
    assert turned > 0  # the rod did turn on landing: the check saw it turned


def test_3d_rigid_bodies_are_replayed_as_meshes_that_move(tmp_path: Path) -> None:
    # box-edge-3d: a 0.4 x 0.3 x 0.2 m box lands on an edge on a static slab and turns. Its
    # mesh is logged once in its own frame (12 triangles whose corners are the box's eight,
    # (+-0.2, +-0.15, +-0.1) m, normals outward); its pose every frame is the trajectory's
    # centre and quaternion; the slab, which never moves, has one static pose.
    out, data = _replayed(tmp_path, "box-edge-3d", "0.4")
    with h5py.File(out / "trajectory.h5", "r") as f:
        x = f["particles/all/position/value"][()]
        q = f["particles/all/orientation/value"][()]
        mass = f["particles/all/mass"][()]
    box, slab = (
        int(np.flatnonzero(np.isfinite(mass))[0]),
        int(np.flatnonzero(~np.isfinite(mass))[0]),
    )
    mesh = data[f"/world/meshes/{box}"]
    shape = mesh[-1]  # the static part: the mesh itself
    corners = np.stack(shape["vertex_positions"])
    assert corners.shape == (36, 3)
    # every triangle corner is a box corner (float32: 1e-7 m covers half an ulp)
    np.testing.assert_allclose(np.abs(corners), [[0.2, 0.15, 0.1]] * 36, rtol=0, atol=1e-7)
    normals = np.stack(shape["vertex_normals"]).reshape(12, 3, 3)[:, 0]
    centres = corners.reshape(12, 3, 3).mean(axis=1)
    assert np.all(np.sum(normals * centres, axis=1) > 0.0)  # outward
    frames = sorted(k for k in mesh if k >= 0)
    assert frames == list(range(x.shape[0]))
    turned = 0
    for k in frames:
        np.testing.assert_allclose(np.ravel(mesh[k]["translation"]), x[k, box], rtol=1e-6)
        xyzw = np.ravel(mesh[k]["quaternion"])
        np.testing.assert_allclose(xyzw, q[k, box][[1, 2, 3, 0]], rtol=0, atol=1e-7)
        turned += abs(abs(float(q[k, box] @ q[0, box])) - 1.0) > 1e-4
    assert turned > 0  # it did turn on landing
    still = data[f"/world/meshes/{slab}"]
    assert sorted(still) == [-1]  # one static pose and mesh, no frames
    np.testing.assert_allclose(np.ravel(still[-1]["translation"]), x[0, slab], rtol=1e-6)
