"""Write the seven two-sphere cases of ``carom.studies.two_spheres`` as built-in scenes
(case-1.toml ...).

Each scene starts the spheres half a second before the contact configuration of its case, so
they meet at t = 0.5 s exactly as the case states, and runs to t = 1 s. The box is sized to
hold both paths with a margin, so no wall is reached. tests/test_scenarios.py checks that
every scene reproduces its case. Run from the repository root:

    python scripts/make_case_scenes.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from carom.reference.exact import smooth_exact
from carom.studies.two_spheres import CASES

T_CONTACT = 0.5  # s
UNTIL = 1.0  # s
MARGIN = 0.2  # m beyond the spheres' reach

folder = Path(__file__).resolve().parent.parent / "src" / "carom" / "scenarios"
for case in CASES:
    e = case.restitutions[0]
    x = np.array([case.x1, case.x2], dtype=float)
    v = np.array([case.v1, case.v2], dtype=float)
    after = np.array(smooth_exact(case.x1, case.v1, case.m1, case.x2, case.v2, case.m2, e)[:2])
    # the spheres' reach over [0, UNTIL]: start points, contact points, end points
    reach = np.concatenate([x - v * T_CONTACT, x, x + after * (UNTIL - T_CONTACT)])
    low = reach.min(axis=0) - case.radius - MARGIN
    high = reach.max(axis=0) + case.radius + MARGIN
    box = np.ceil((high - low) * 10) / 10  # whole decimetres
    shift = -low + (box - (high - low)) / 2  # centre the paths in the box
    start = x - v * T_CONTACT + shift
    kind = {1.0: "elastic", 0.0: "perfectly plastic"}.get(e, f"e = {e}")
    description = (
        f"Case {case.number} of the two-sphere study ('carom cases'), {kind}: "
        f"m1 = {case.m1:g} kg, m2 = {case.m2:g} kg, radius {case.radius:g} m. The spheres "
        f"touch at t = {T_CONTACT} s in the configuration the study states (sphere 2 at "
        f"[{shift[0]:.6g}, {shift[1]:.6g}])."
    )
    rows = {
        name: ", ".join(f"[{float(a)!r}, {float(b)!r}]" for a, b in value)
        for name, value in (("positions", start), ("velocities", v))
    }
    text = f"""[scene]
title = "Two spheres, case {case.number}: {case.title}"
description = "{description}"

[world]
dimension = 2
box = [{box[0]:.1f}, {box[1]:.1f}]

[[materials]]
name = "case"
restitution = {e!r}

[[bodies]]
positions = [{rows["positions"]}]
velocities = [{rows["velocities"]}]
radius = {case.radius!r}
mass = [{case.m1!r}, {case.m2!r}]
material = "case"

[run]
until = {UNTIL}
frame_interval = 0.01
"""
    (folder / f"case-{case.number}.toml").write_text(text)
    print(f"wrote case-{case.number}.toml")
