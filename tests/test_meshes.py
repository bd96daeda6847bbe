"""carom.meshes: mesh files, static meshes, and concave dynamic bodies cut by CoACD with the
closed mesh's exact mass properties, kept beside the file."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from carom.errors import CaromError
from carom.geometry.mass3d import polyhedron_integrals
from carom.meshes import (
    CACHE_SUFFIX,
    Mesh,
    bowl_mesh,
    decompose,
    load_mesh,
    save_obj,
    terrain_mesh,
    torus_mesh,
)
from carom.shapes3d import Box

trimesh = pytest.importorskip("trimesh")
pytest.importorskip("coacd")
pytest.importorskip("scipy")

MAJOR, MINOR = 0.1, 0.03  # a torus's ring and tube radii [m]


def _torus(sections: int = 32, tube: int = 16) -> Mesh:
    t = trimesh.creation.torus(
        major_radius=MAJOR, minor_radius=MINOR, major_sections=sections, minor_sections=tube
    )
    return Mesh(np.asarray(t.vertices), np.asarray(t.faces))


def test_a_mesh_file_loads_as_a_static_mesh(tmp_path: Path) -> None:
    path = tmp_path / "box.stl"
    trimesh.creation.box(extents=[1.0, 2.0, 3.0]).export(path)
    mesh = load_mesh(path, scale=0.5)
    assert np.asarray(mesh.vertices).shape == (8, 3)
    assert np.asarray(mesh.triangles).shape == (12, 3)
    assert mesh.is_closed()
    assert np.allclose(np.ptp(np.asarray(mesh.vertices), axis=0), [0.5, 1.0, 1.5])
    with pytest.raises(CaromError, match="no mass"):
        mesh.mass_properties(density=1.0)


def test_the_polyhedral_torus_has_its_closed_form() -> None:
    # The torus V = 2 pi^2 R r^2, I_zz = m (R^2 + 3 r^2/4), I_xx = m (R^2/2 + 5 r^2/8). Its
    # mesh of n ring and k tube sections is inscribed: each circle becomes a polygon, which
    # keeps sin(a)/a of the area for a = 2 pi/n (and 2 pi/k), and the mesh's volume is exactly
    # V (n sin(2 pi/n)/2 pi)(k sin(2 pi/k)/2 pi) (to round-off). The inertia per unit mass
    # carries a chord error of the same second order; it is held to half the volume's defect.
    for n, k in ((32, 16), (64, 32)):
        mesh = _torus(n, k)
        solid = polyhedron_integrals(np.asarray(mesh.vertices), np.asarray(mesh.triangles))
        kept = (n * math.sin(2 * math.pi / n) / (2 * math.pi)) * (
            k * math.sin(2 * math.pi / k) / (2 * math.pi)
        )
        volume = 2 * math.pi**2 * MAJOR * MINOR**2
        assert solid.volume == pytest.approx(volume * kept, rel=1e-12)
        inertia = (
            np.trace(solid.second_about_centroid()) * np.eye(3) - solid.second_about_centroid()
        )
        per_mass = np.diag(inertia) / solid.volume
        exact = [MAJOR**2 / 2 + 5 * MINOR**2 / 8] * 2 + [MAJOR**2 + 3 * MINOR**2 / 4]
        assert np.all(np.abs(per_mass / exact - 1) <= (1 - kept) / 2)


def test_a_torus_file_is_cut_once_and_its_pieces_kept_beside_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "torus.obj"
    mesh = _torus()
    trimesh.Trimesh(np.asarray(mesh.vertices), np.asarray(mesh.triangles)).export(path)
    body = decompose(path)
    kept = tmp_path / ("torus.obj" + CACHE_SUFFIX)
    assert kept.is_file()
    # a ring cannot be one convex piece; the pieces hold the ring's corners
    assert len(body.pieces()) >= 4
    # the mass is the closed mesh's, not the overlapping pieces' sum
    loaded = load_mesh(path)
    exact = polyhedron_integrals(np.asarray(loaded.vertices), np.asarray(loaded.triangles))
    props = body.mass_properties(density=1000.0)
    assert props.mass == pytest.approx(1000.0 * exact.volume, rel=1e-12)
    assert np.max(np.abs(props.centroid)) < 1e-12

    # a second cut reads the file: CoACD is not called again, the pieces are the same
    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("CoACD ran again")

    monkeypatch.setattr("carom.meshes._run_coacd", refuse)
    again = decompose(path)
    assert len(again.pieces()) == len(body.pieces())
    for a, b in zip(again.pieces(), body.pieces(), strict=True):
        assert np.array_equal(a.vertices, b.vertices)
    # another threshold is another cut
    with pytest.raises(AssertionError, match="CoACD ran again"):
        decompose(path, threshold=0.1)


def test_a_file_in_the_way_of_the_cache_is_never_overwritten(tmp_path: Path) -> None:
    path = tmp_path / "box.obj"
    trimesh.creation.box(extents=[1.0, 1.0, 1.0]).export(path)
    mine = tmp_path / ("box.obj" + CACHE_SUFFIX)
    mine.write_text("my notes")
    with pytest.raises(CaromError, match="not carom's pieces file"):
        decompose(path)
    assert mine.read_text() == "my notes"
    body = decompose(path, cache=False)  # and without the cache it still cuts
    assert body.mass_properties(mass=1.0).inertia[0, 0] == pytest.approx(1 / 6, rel=1e-12)


def test_a_piece_too_thin_to_be_a_solid_is_refused_and_nothing_is_kept(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # CoACD may cut a sliver into a piece with no volume (issue 45's corpus: "surface is
    # open", and the pieces file left beside the mesh); here it is made to return a flat one
    import carom.meshes

    path = tmp_path / "box.obj"
    trimesh.creation.box(extents=[1.0, 1.0, 1.0]).export(path)
    flat = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]])
    monkeypatch.setattr(carom.meshes, "_run_coacd", lambda *args: [flat])
    with pytest.raises(CaromError, match=r"box\.obj: CoACD cut piece 0 of 1 too thin"):
        decompose(path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.obj"]


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: Mesh([[0, 0, 0], [1, 0, 0], [0, math.nan, 0]], [[0, 1, 2]]), "vertex 2"),
        (lambda: Mesh([[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 1, 2]]), "no area"),
        (lambda: Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]]), r"outside 0\.\.2"),
        (lambda: Mesh([[0, 0, 0], [1, 0, 0]], [[0, 1, 1]]), "V >= 3"),
        (lambda: load_mesh("/nonexistent/mug.obj"), "no such mesh file"),
        (lambda: terrain_mesh(0, 1.0), "k >= 1 squares"),
        (lambda: decompose(Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])), "at least 4"),
    ],
)
def test_bad_meshes_are_refused(build: object, message: str) -> None:
    with pytest.raises(CaromError, match=message):
        build()  # type: ignore[operator]


def test_open_and_inward_meshes_cannot_be_solids() -> None:
    piece = Box([1.0, 1.0, 1.0]).pieces()[0]
    with pytest.raises(CaromError, match="not closed"):
        decompose(Mesh(piece.vertices, piece.triangles[1:]))
    with pytest.raises(CaromError, match="turn inward"):
        decompose(Mesh(piece.vertices, piece.triangles[:, [0, 2, 1]]))


def test_generated_torus_and_bowl(tmp_path: Path) -> None:
    # the torus generator's polyhedron: the volume of a ring of n sections of a k-gon is
    # 2 pi^2 R r^2 times (n sin(2 pi/n) / 2 pi) (k sin(2 pi/k) / 2 pi) (Pappus, on polygons)
    major, minor, n, k = 0.15, 0.04, 16, 8
    torus = torus_mesh(major, minor, n, k)
    assert torus.is_closed()
    solid = polyhedron_integrals(np.asarray(torus.vertices), np.asarray(torus.triangles))
    shortfall = (n * math.sin(2 * math.pi / n) / (2 * math.pi)) * (
        k * math.sin(2 * math.pi / k) / (2 * math.pi)
    )
    # the polygon's centroid sits off the ring's centre line only through its own symmetry:
    # none for a regular k-gon, so Pappus holds with the polygon's area and the n-gon's sides
    area = 0.5 * k * minor**2 * math.sin(2 * math.pi / k)
    pappus = n * math.sin(2 * math.pi / n) * major * area  # n prisms' frusta, exactly
    assert solid.volume == pytest.approx(pappus, rel=1e-12)
    assert pappus == pytest.approx(2 * math.pi**2 * major * minor**2 * shortfall, rel=1e-12)
    # the bowl: open, every triangle facing its centre (the side bodies stay on)
    bowl = bowl_mesh(0.5, 24, 6)
    assert not bowl.is_closed()
    corners = np.asarray(bowl.vertices)[np.asarray(bowl.triangles)]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.all(np.einsum("ij,ij->i", normal, -corners.mean(axis=1)) > 0.0)
    # written as OBJ and read back: the same mesh
    save_obj(torus, tmp_path / "ring.obj")
    again = load_mesh(tmp_path / "ring.obj")
    assert np.asarray(again.triangles).shape == np.asarray(torus.triangles).shape
    back = polyhedron_integrals(np.asarray(again.vertices), np.asarray(again.triangles))
    assert back.volume == pytest.approx(solid.volume, rel=1e-10)


def test_pieces_go_to_the_users_cache_when_the_folder_cannot_take_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the mesh's folder refuses the cache (here a folder sits where its temporary file would
    # go); the pieces are kept in $XDG_CACHE_HOME/carom/pieces instead and reused from there
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    folder = tmp_path / "shipped"
    folder.mkdir()
    path = folder / "ring.obj"
    save_obj(torus_mesh(0.15, 0.04, 12, 6), path)
    (folder / ("ring.obj" + CACHE_SUFFIX + ".partial.npz")).mkdir()
    body = decompose(path)
    assert not (folder / ("ring.obj" + CACHE_SUFFIX)).exists()
    kept = list((tmp_path / "cache" / "carom" / "pieces").glob("*" + CACHE_SUFFIX))
    assert len(kept) == 1

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("CoACD ran again")

    monkeypatch.setattr("carom.meshes._run_coacd", refuse)
    again = decompose(path)
    assert len(again.pieces()) == len(body.pieces())
    # a mesh with no file at all is kept there too
    monkeypatch.undo()
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    decompose(torus_mesh(0.2, 0.05, 12, 6))
    assert len(list((tmp_path / "cache" / "carom" / "pieces").glob("*" + CACHE_SUFFIX))) == 2


def test_a_mesh_file_with_a_vertex_that_is_not_a_number_is_refused(tmp_path: Path) -> None:
    # issue 45: trimesh's processing dropped the vertex and its triangle, and the run went on
    # with one of two triangles
    pytest.importorskip("trimesh")
    file = tmp_path / "nan.obj"
    file.write_text("v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n")
    with pytest.raises(CaromError, match=r"nan\.obj: vertex 3 = \[0\.0, nan, 0\.0\] is not a"):
        load_mesh(file)


def test_a_mesh_file_in_an_encoding_trimesh_cannot_read_is_one_message(tmp_path: Path) -> None:
    # issue 45: once "No module named 'charset_normalizer'"
    pytest.importorskip("trimesh")
    file = tmp_path / "bad.stl"
    file.write_bytes(b"solid bad\n facet normal 0 0 1\n\xff\xfe\xfa outer loop\n")
    with pytest.raises(CaromError, match=r"bad\.stl: cannot read it as a mesh") as caught:
        load_mesh(file)
    assert "module" not in str(caught.value)


def test_a_meshs_triangles_are_one_block_laid_out_as_triangle_pieces() -> None:
    # issue 45: a static mesh's triangles are held as one block (two arrays), not an object a
    # triangle (2e6 of them took 40 s to add and 86 s to build); the engine's arrays must be
    # those of the triangles one by one (triangle_piece), and a saved block comes back whole
    import carom
    from carom.bodies import pieces_from_arrays, pieces_to_arrays
    from carom.engines.rigid3d.model import build_model, triangle_piece
    from carom.shapes3d import TrianglePieces

    mesh = _torus(12, 8)
    world = carom.World(3, [1.0, 1.0, 1.0])
    i = world.add_body(mesh, [0.0, 0.0, 0.0], kind="static")
    block = world.bodies.pieces[i]
    assert isinstance(block, TrianglePieces)
    corners = np.asarray(mesh.vertices)[np.asarray(mesh.triangles)]
    np.testing.assert_array_equal(block.corners(), corners)

    def model(pieces: object) -> object:
        inf = np.array([np.inf])
        return build_model(
            [pieces], np.array([2]), inf, np.full((1, 3, 3), np.inf), np.zeros(1, np.int64),
            np.ones((1, 1)), np.ones((1, 1)), np.zeros((1, 1)), np.zeros(3),
        )  # fmt: skip

    whole = model(block)
    one_by_one = model([triangle_piece(c) for c in corners])
    for name, value in whole._asdict().items():  # type: ignore[attr-defined]
        other = getattr(one_by_one, name)
        assert value.dtype == other.dtype, name
        # normals: a row's norm summed in another order may differ in the last bit
        np.testing.assert_allclose(value, other, rtol=4e-16, atol=0.0, err_msg=name)

    box = Box([0.1, 0.2, 0.3]).pieces()
    arrays = pieces_to_arrays([box, (), block, box], 3)
    back = pieces_from_arrays(arrays, 4)
    assert back[1] == ()
    assert isinstance(back[2], TrianglePieces)
    np.testing.assert_array_equal(back[2].corners(), corners)
    for k in (0, 3):
        assert len(back[k]) == 1
        np.testing.assert_array_equal(back[k][0].vertices, box[0].vertices)
        np.testing.assert_array_equal(back[k][0].triangles, box[0].triangles)
