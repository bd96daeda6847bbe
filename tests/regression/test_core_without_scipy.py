"""Regression: the 3D contact and impact kernels multiplied vectors with "@", which Numba
compiles to BLAS calls through SciPy; without SciPy (the core is NumPy and Numba only) they
failed to compile with "scipy 0.16+ is required for linear algebra"."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = """
import sys
sys.modules["scipy"] = None  # as if SciPy were not installed
import numpy as np
from carom.geometry import manifold3d as m
from carom.geometry.polyhedron import triangle_features
from carom.laws.rigid_impact import collision_matrix, point_impulse

out, ids = np.zeros(m.OUT_SIZE), np.zeros(m.MAX_POINTS, np.int64)
a, b = np.zeros(3), np.array([0.0, 0.0, 1.5])
m.contact_sphere_sphere(a, 1.0, b, 1.0, 0.0, out, ids)
m.contact_capsule_capsule(a, b, 0.1, a + 1.0, b + 1.0, 0.1, 1.0, out, ids)
m.contact_segments_plane(np.zeros((2, 3)), 0.1, np.array([0.0, 0.0, 1.0]), 0.0, 0.1, out, ids)
tri = triangle_features(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]))
m.contact_hull_hull(*tri, *tri, 0.1, 0.005, out, ids)
m.contact_hull_sphere(*tri, b, 0.1, 5.0, out, ids)
m.contact_hull_capsule(*tri, a + 0.2, b, 0.1, 5.0, 0.005, out, ids)
k = collision_matrix(1.0, np.eye(3), a, 1.0, np.eye(3), b)
print(point_impulse(np.array([0.0, 0.0, -1.0]), np.array([0.0, 0.0, 1.0]), k, 0.5, 0.3)[2])
"""


@pytest.mark.slow  # (a fresh process compiles every 3D kernel)
@pytest.mark.needs_jit
def test_the_3d_kernels_compile_without_scipy(tmp_path: Path) -> None:
    # a fresh kernel cache, so everything compiles here; SciPy blocked before Numba looks
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr[-2000:]
    # unit masses and tensors, the offsets along n: n . K n = 2 and no slip, so the impulse is
    # Hecker's j n with j = (1 + e) |u_n| / (n . K n) = 1.5 / 2
    assert float(done.stdout.strip()) == pytest.approx(0.75, rel=1e-12)
