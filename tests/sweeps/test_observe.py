"""The task of a sweep (run_point) in this process: what it records when a point cannot run."""

from __future__ import annotations

from pathlib import Path

from carom.sweeps import load_sweep
from carom.sweeps.observe import run_point


def test_a_rigid_run_must_end_on_a_step(tmp_path: Path) -> None:
    # the pyramid steps at 60 Hz: 0.51 s is 30.6 steps, refused by name with the nearest
    # whole number of steps; 0.5 s is 30 steps and runs
    path = tmp_path / "sweep.toml"
    for until, words in ((0.51, "until = 0.51 s is not a whole number"), (0.5, "")):
        path.write_text(
            f'[sweep]\nscene = "pyramid"\nuntil = {until}\nwarmup = 0.25\n'
            'observables = ["stack_drift"]\n[parameters]\n"materials.0.friction" = [0.6]\n'
        )
        spec = load_sweep(path)
        out = run_point(spec.task(spec.points()[0]))
        if words:
            assert out["status"] == "failed"
            assert words in out["message"]
            assert "0.516667 s (31 steps)" in out["message"]
        else:
            assert out["status"] == "ok", out["message"]
            assert out["values"]["stack_drift"] > 0.0  # (the cannonball's flight, from 0.25 s)
