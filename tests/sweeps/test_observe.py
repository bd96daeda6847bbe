"""The task of a sweep (run_point) in this process: what it records for a point."""

from __future__ import annotations

from pathlib import Path

from carom.sweeps import load_sweep
from carom.sweeps.observe import run_point


def test_a_rigid_run_ends_on_its_until_whatever_the_step(tmp_path: Path) -> None:
    # issue 45: the pyramid steps at 60 Hz, and 0.51 s (30.6 steps) failed every row while
    # the sweep's other checks refuse before anything runs. A sweep records no frames, so
    # the engine now ends on until with a shorter last step: both points run, and the
    # cannonball flies on from 0.25 s in each
    path = tmp_path / "sweep.toml"
    for until in (0.51, 0.5):
        path.write_text(
            f'[sweep]\nscene = "pyramid"\nuntil = {until}\nwarmup = 0.25\n'
            'observables = ["stack_drift"]\n[parameters]\n"materials.0.friction" = [0.6]\n'
        )
        spec = load_sweep(path)
        out = run_point(spec.task(spec.points()[0]))
        assert out["status"] == "ok", out["message"]
        assert out["values"]["stack_drift"] > 0.0
