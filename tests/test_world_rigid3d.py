"""3D rigid bodies in a World: adding them, refusing what cannot be, saving and loading."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import carom
from carom.engines.stepped.settings import RigidSettings
from carom.errors import CaromError
from carom.meshes import Mesh
from carom.shapes import Box as Box2D
from carom.shapes3d import Box, Capsule, Hull, Plane, Sphere, rotation_matrix


def _floor_world() -> carom.World:
    world = carom.World(3, box=[4, 4, 4], boundary="open", gravity=[0, 0, -9.81])
    world.add_plane([0, 0, 0], [0, 0, 1], material=carom.Material(0.3, friction=0.5))
    return world


def test_a_3d_body_runs_the_3d_rigid_engine() -> None:
    world = _floor_world()
    i = world.add_body(Box([0.2, 0.2, 0.2]), [0, 0, 0.5])
    assert i == 0
    assert world.engine_name == "rigid"
    world.run(until=0.1)
    assert type(world.engine).__name__ == "RigidEngine3D"
    # 0.1 s of free fall from rest (exact in free flight): z = 0.5 - g t^2 / 2
    assert world.positions[0, 2] == pytest.approx(0.5 - 9.81 * 0.01 / 2, rel=1e-12)
    assert world.orientations.shape == (1, 4)


def test_orientation_turns_the_shape_about_its_origin() -> None:
    # a capsule along z turned a quarter turn about y lies along x: its lowest point is its
    # radius below the centre, and it rests on the floor at that height
    world = _floor_world()
    quarter = [math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0]
    world.add_body(Capsule(1.0, 0.1), [0, 0, 0.1], orientation=quarter)
    axis = rotation_matrix(world.orientations[0]) @ [0, 0, 1]
    assert axis == pytest.approx([1, 0, 0], abs=1e-15)
    world.run(until=0.5)
    assert world.positions[0, 2] == pytest.approx(0.1, abs=1e-3)
    # the same turn as a matrix gives the same quaternion
    other = _floor_world()
    other.add_body(Capsule(1.0, 0.1), [0, 0, 0.1], orientation=rotation_matrix(quarter))
    assert other.orientations[0] == pytest.approx(np.array(quarter), abs=1e-15)


def test_centre_of_mass_of_an_off_centre_shape_is_the_bodys_position() -> None:
    # a compound of two unit cubes at x = 0 and x = 1: its centre of mass is at x = 0.5 of
    # its frame; turned half a turn about z and put at the origin it sits at x = -0.5
    shape = carom.shapes3d.Compound([Box([1, 1, 1]), (Box([1, 1, 1]), [1.0, 0.0, 0.0])])
    world = carom.World(3, box=[4, 4, 4], boundary="open")
    world.add_body(shape, [0, 0, 0], orientation=[0.0, 0.0, 0.0, 1.0])
    assert world.positions[0] == pytest.approx([-0.5, 0.0, 0.0], abs=1e-15)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda w: w.add_body(Box([1, 1, 1]), [0, 0, 0], angle=0.3), "angles= is for 2D"),
        (lambda w: w.add_body(Box([1, 1, 1]), [0, 0, 0], orientation=[1, 0, 0]), "quaternions"),
        (lambda w: w.add_body(Box([1, 1, 1]), [0, 0, 0], orientation=[0, 0, 0, 0]), "no rotation"),
        (lambda w: w.add_body(Box2D(1, 1), [0, 0, 0]), "2D shape"),
        (lambda w: w.add_body(Plane(), [0, 0, 0], kind="static"), "add_plane"),
        (
            lambda w: w.add_body(Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]), [0, 0, 0]),
            "kind='static'",
        ),
        (lambda w: w.add_body(Box([1, 1, 1]), [0, 0, 0], kind="static", mass=1.0), "no mass"),
        (
            lambda w: w.add_body(Box([1, 1, 1]), [0, 0, 0], angular_velocity=[1, 0]),
            "angular_velocities",
        ),
    ],
)
def test_bad_3d_bodies_are_refused_with_the_reason(call, message) -> None:
    world = carom.World(3, box=[4, 4, 4], boundary="open")
    with pytest.raises(CaromError, match=message):
        call(world)
    assert world.n_bodies == 0  # nothing half-added


def test_a_3d_shape_in_a_2d_world_is_refused() -> None:
    world = carom.World(2, box=[4, 4], boundary="open")
    with pytest.raises(CaromError, match="3D shape"):
        world.add_body(Sphere(0.1), [0, 0])


def test_overlapping_3d_bodies_are_refused_at_the_start() -> None:
    world = carom.World(3, box=[4, 4, 4], boundary="open")
    world.add_body(Box([1, 1, 1]), [0, 0, 0])
    world.add_body(Box([1, 1, 1]), [0.5, 0, 0])
    with pytest.raises(CaromError, match=r"overlap by 0\.5 m"):
        world.run(until=0.1)


def test_static_mesh_holds_a_ball() -> None:
    # a ball dropped on a two-triangle static square comes to rest on it, its centre one
    # radius above (less the soft contact's 7e-5 m)
    world = carom.World(3, box=[4, 4, 4], boundary="open", gravity=[0, 0, -9.81])
    square = Mesh([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    world.add_body(square, [0, 0, 0], kind="static", material=carom.Material(0.0, friction=0.5))
    world.add_body(Sphere(0.1), [0.2, 0.1, 0.3], material=carom.Material(0.0, friction=0.5))
    world.run(until=2.0)
    assert world.positions[1] == pytest.approx([0.2, 0.1, 0.1], abs=1e-4)


def test_walls_keep_3d_bodies_in_the_box() -> None:
    world = carom.World(3, box=[1, 1, 1], boundary="walls", gravity=[0, 0, -9.81])
    world.add_body(Box([0.1, 0.1, 0.1]), [0.5, 0.5, 0.5], velocity=[3, -2, 1])
    world.run(until=2.0)
    assert np.all(world.positions > 0.0)
    assert np.all(world.positions < 1.0)


def _tumbling() -> carom.World:
    world = _floor_world()
    world.add_body(Box([0.2, 0.3, 0.4]), [0, 0, 0.5], angular_velocity=[1, 2, 3])
    world.add_body(Sphere(0.1), [0.5, 0, 0.5], material=carom.Material(0.5, rolling=1e-3))
    return world


def _pile() -> carom.World:
    """Boxes, balls and hulls dropped onto a stack of slabs, sleep off: settled by 2 s, when
    most of its manifolds are kept from step to step (carom.engines.rigid3d.contacts)."""
    rng = np.random.default_rng(7)
    world = carom.World(3, box=[4, 4, 4], boundary="open", gravity=[0, 0, -9.81],
                        rigid=RigidSettings(sleep=False))  # fmt: skip
    world.add_plane([0, 0, 0], [0, 0, 1], material=carom.Material(0.2, friction=0.6))
    rock = Hull(rng.normal(size=(10, 3)) * 0.1)
    for k in range(4):
        turn = 0.025 * k  # half the yaw, as a quaternion (w, 0, 0, z)
        world.add_body(Box([0.6, 0.6, 0.3]), [0.02 * k, 0, 0.15 + 0.3 * k],
                       orientation=[math.cos(turn), 0.0, 0.0, math.sin(turn)])  # fmt: skip
    for k in range(6):
        q = rng.normal(size=4)
        world.add_body([Box([0.2, 0.2, 0.2]), Sphere(0.1), rock][k % 3],
                       [0.15 * (k % 2) - 0.07, 0.15 * (k // 2 % 2) - 0.07, 1.6 + 0.4 * k],
                       orientation=q / np.linalg.norm(q))  # fmt: skip
    return world


@pytest.mark.parametrize(
    ("build", "half", "until"), [(_tumbling, 0.5, 1.0), (_pile, 2.0, 2.5)], ids=["tumbling", "pile"]
)
def test_save_and_load_continue_bit_for_bit(
    tmp_path: Path, build: Callable[[], carom.World], half: float, until: float
) -> None:
    # The checkpoint holds everything a step reads: poses, warm-start impulses, and the
    # manifolds kept from step to step (the pile fails without them).
    straight = build()
    straight.run(until=until)
    saved = build()
    saved.run(until=half)
    saved.save(tmp_path / "w.npz")
    loaded = carom.World.load(tmp_path / "w.npz")
    loaded.run(until=until)
    for name in ("positions", "velocities", "orientations", "angular_velocities"):
        assert np.array_equal(getattr(loaded, name), getattr(straight, name)), name


def test_observables_use_the_turned_inertia_tensor() -> None:
    # a 1 x 2 x 3 box turned and spinning about a skew axis: its angular momentum is
    # R I R^T w (plus the orbit m x × v), its rotational energy w . R I R^T w / 2; the
    # World's statistics agree with them, to round-off
    from carom.observables import angular_momentum, rotational_energy

    world = carom.World(3, box=[4, 4, 4], boundary="open")
    q = np.array([0.8, 0.2, -0.4, 0.4])
    q /= np.linalg.norm(q)
    w = np.array([0.3, -1.2, 2.0])
    world.add_body(Box([1.0, 2.0, 3.0]), [1, 2, 3], velocity=[0.5, 0, 0], orientation=q,
                   angular_velocity=w, mass=6.0)  # fmt: skip
    r = rotation_matrix(world.orientations[0])
    inertia = r @ world.bodies.inertia_tensor[0] @ r.T
    x, v = world.positions, world.velocities
    expected = inertia @ w + 6.0 * np.cross(x[0], v[0])
    got = angular_momentum(world.bodies, x, v, world.angular_velocities, world.orientations)
    assert got == pytest.approx(expected, rel=1e-14)
    spin = rotational_energy(world.bodies, world.angular_velocities, world.orientations)
    assert spin == pytest.approx(0.5 * w @ inertia @ w, rel=1e-14)
    assert world.stats.kinetic_energy == pytest.approx(spin + 0.5 * 6.0 * 0.25, rel=1e-14)


def test_spheres_inertia_tensors_are_made_until_another_shape_comes() -> None:
    # A world of spheres stores no inertia tensor (72 bytes a sphere); it makes, on each read,
    # diag(q m a^2) (PHYSICS.md: I = q m a^2, q = 2/5 for a solid sphere), inf for a static
    # sphere. Once a box comes, every tensor is stored, the spheres' with the same values, the
    # box's its own: a solid cuboid's m (b^2 + c^2) / 12 on the diagonal (any mechanics text).
    world = carom.World(3, box=[5, 5, 5])
    world.add_spheres([[1, 1, 1], [3, 3, 3]], radius=0.4, mass=[1.0, 2.0])
    world.add_static_spheres([[2, 2, 4]], radius=0.3)
    tensor = world.bodies.inertia_tensor
    assert world.bodies.inertia_tensor is not tensor  # made again on each read
    for i, (m, a) in enumerate([(1.0, 0.4), (2.0, 0.4)]):
        np.testing.assert_array_equal(tensor[i], np.diag([0.4 * m * a**2] * 3))  # q = 2/5
    np.testing.assert_array_equal(np.diag(tensor[2]), [np.inf] * 3)
    np.testing.assert_array_equal(tensor[2][~np.eye(3, dtype=bool)], np.zeros(6))
    world.add_body(Box([0.2, 0.4, 0.6]), [2.5, 1, 1], mass=3.0)
    world.add_spheres([[4, 4, 1]], radius=0.2)
    stored = world.bodies.inertia_tensor
    assert world.bodies.inertia_tensor is stored  # kept from now on
    assert stored.shape == (5, 3, 3)
    np.testing.assert_array_equal(stored[:3], tensor)
    box = np.diag([0.4**2 + 0.6**2, 0.2**2 + 0.6**2, 0.2**2 + 0.4**2]) * 3.0 / 12.0
    np.testing.assert_allclose(stored[3], box, rtol=1e-14)
    np.testing.assert_array_equal(stored[4], np.diag([0.4 * 1.0 * 0.2**2] * 3))
