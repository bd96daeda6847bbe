"""Reading a scene for the peers: what they can represent, and restitution per surface."""

from __future__ import annotations

import numpy as np
import pytest

from carom.compare.driver import peer_scene
from carom.compare.spec import factor_restitution
from carom.errors import CaromError
from carom.scene import Scene


def _two(restitutions, combine="mean", walls=1.0):
    return Scene.from_dict(
        {
            "world": {
                "dimension": 2,
                "box": [2.0, 1.0],
                "combine": combine,
                "walls": walls,
            },
            "materials": [{"name": f"m{k}", "restitution": e} for k, e in enumerate(restitutions)],
            "bodies": [
                {"positions": [[0.5 + k * 0.5, 0.5]], "radius": 0.1, "material": f"m{k}"}
                for k in range(len(restitutions))
            ],
            "run": {"until": 1.0},
        }
    )


def test_one_restitution_splits_into_square_roots():
    spec = peer_scene(_two([0.64, 0.64], walls=0.8), name="two")
    body, wall, _, exact = factor_restitution(spec, "pymunk")
    # sqrt(0.64) rounds to within an ulp of 0.8 (1.4e-16 relative)
    np.testing.assert_allclose(body, [0.8, 0.8], rtol=1e-15)
    # the product rule then gives e_pair = 0.8^2 = 0.64 and e_wall = 0.8 x 1 = 0.8
    np.testing.assert_allclose(wall, [1.0] * 4, rtol=1e-15)
    assert exact


def test_a_product_scene_factorises_and_a_mean_scene_does_not():
    body, _, _, _ = factor_restitution(peer_scene(_two([0.25, 1.0], "product"), name="p"), "x")
    # carom's product rule: e_ij = e_i e_j, so the coefficients are the restitutions
    np.testing.assert_allclose(body, [0.25, 1.0], rtol=1e-15)
    with pytest.raises(CaromError, match=r"pair \(0, 1\) at e = 0.625"):
        factor_restitution(peer_scene(_two([0.25, 1.0], "mean"), name="m"), "pymunk")


def test_plastic_bodies_against_bouncy_walls_are_flagged():
    _, _, notes, exact = factor_restitution(peer_scene("case-7"), "pybullet")
    assert not exact
    assert any("plastic" in note for note in notes)


@pytest.mark.parametrize(
    ("scene", "what"),
    [
        ("hard-sphere-gas", "periodic"),
        ("galton-board", "static bodies"),
    ],
)
def test_what_the_peers_cannot_represent_is_refused_by_name(scene, what):
    with pytest.raises(CaromError, match=what):
        peer_scene(scene)


def test_rough_materials_are_refused():
    scene = Scene.from_dict(
        {
            "world": {"dimension": 2, "box": [2.0, 1.0]},
            "materials": [{"name": "rough", "restitution": 1.0, "beta": 0.5}],
            "bodies": [{"positions": [[0.5, 0.5]], "radius": 0.1, "material": "rough"}],
            "run": {"until": 1.0},
        }
    )
    with pytest.raises(CaromError, match="rough or frictional"):
        peer_scene(scene, name="rough")


def test_steps_reach_until_without_rounding_drift():
    spec = peer_scene("case-1")
    assert spec.steps(1 / 60) == 60
    assert spec.steps(0.002) == 500
    assert spec.steps(0.3) == 4
