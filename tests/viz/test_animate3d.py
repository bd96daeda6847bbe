"""3D rigid bodies in animations: their pieces' faces, tessellated, turned and shaded."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from carom.shapes3d import Box, Capsule, Sphere
from carom.viz.animate import Facets
from tests.cli.helpers import carom


def _volume(triangles: np.ndarray) -> float:
    """Signed volume enclosed by triangles (T, 3, 3), positive when they face outward."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


@pytest.mark.parametrize(
    ("shape", "bound"),
    [
        (Box([0.2, 0.3, 0.4]), (0.024, 0.024)),
        (Sphere(0.1), (0.8 * 4 / 3 * math.pi * 1e-3, 4 / 3 * math.pi * 1e-3)),
        (Capsule(0.3, 0.1), (0.8 * (math.pi * 0.01 * 0.3 + 4 / 3 * math.pi * 1e-3), 0.0136)),
    ],
    ids=["box", "ball", "capsule"],
)
def test_each_piece_is_a_closed_outward_surface(shape, bound) -> None:
    # a box's own triangles enclose its volume exactly; a tessellated ball or capsule is
    # inscribed in the round solid (below its volume, and above 80% of it at 12 x 6)
    facets = Facets([shape.pieces()])
    volume = _volume(facets.corners)
    assert bound[0] - 1e-15 <= volume <= bound[1] + 1e-15
    normal = np.cross(
        facets.corners[:, 1] - facets.corners[:, 0], facets.corners[:, 2] - facets.corners[:, 0]
    )
    outward = np.einsum("ij,ij->i", normal, facets.corners.mean(axis=1))
    assert np.all(outward > 0.0)


def test_faces_are_turned_and_moved_with_their_body() -> None:
    facets = Facets([Capsule(0.4, 0.05).pieces()])
    quarter = [math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0]  # z onto x
    world, normal = facets.placed(np.array([[1.0, 2.0, 3.0]]), np.array([quarter]))
    # the capsule along z, turned onto x and moved: it spans x in 1 -+ (0.2 + 0.05)
    assert world[..., 0].min() == pytest.approx(0.75, abs=1e-12)
    assert world[..., 0].max() == pytest.approx(1.25, abs=1e-12)
    assert np.allclose(np.linalg.norm(normal, axis=1), 1.0)


def test_a_3d_rigid_run_draws_shaded_faces(tmp_path: Path) -> None:
    iio = pytest.importorskip("imageio.v3", reason="the viz extra is missing")
    pytest.importorskip("imageio_ffmpeg", reason="the viz extra is missing")
    out = tmp_path / "dominoes"
    done = carom("run", "dominoes-3d", "--out", out, "--until", "0.2", "--no-plots")
    assert done.returncode == 0, done.stderr
    frame = np.asarray(iio.imread(out / "animation.mp4", index=0))[:, :800]
    # the thirty dominoes, at rest, are dark blue-violet faces (plasma's low end, shaded):
    # thousands of such pixels (without their faces nothing of them would show)
    r, g, b = (frame[..., k].astype(int) for k in range(3))
    blue = (b > r + 30) & (b > g + 30)
    assert blue.sum() > 2000
