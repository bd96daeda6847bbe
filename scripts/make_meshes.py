"""Write the meshes the built-in scenes use (src/carom/scenarios/meshes/), from carom.meshes'
generators: run it after changing them (python scripts/make_meshes.py)."""

from __future__ import annotations

from pathlib import Path

from carom.meshes import bowl_mesh, save_obj, torus_mesh

HERE = Path(__file__).resolve().parent.parent / "src" / "carom" / "scenarios" / "meshes"


def main() -> None:
    HERE.mkdir(exist_ok=True)
    # a ring 0.3 m across its centre line, 0.08 m thick: 16 x 8 sections, 256 triangles
    save_obj(torus_mesh(0.15, 0.04, around=16, across=8), HERE / "torus.obj")
    # a bowl 0.5 m in radius: 24 corners a ring, 6 rings, 264 triangles
    save_obj(bowl_mesh(0.5, around=24, down=6), HERE / "bowl.obj")


if __name__ == "__main__":
    main()
