"""Small sweeps for the tests: a periodic gas of a few spheres, quick even without the JIT."""

from __future__ import annotations

from pathlib import Path

GAS = """
[world]
dimension = 3
box = [5.0, 5.0, 5.0]
boundary = "periodic"

[[gas]]
count = 20
packing = 0.3
radius = 0.5
seed = 1

[run]
until = 1.0
"""


def write_sweep(folder: Path, parameters: str, *, head: str = "", scene: str = GAS) -> Path:
    """A sweep file in ``folder`` over the gas scene written beside it; ``head`` adds keys to
    [sweep] (its defaults: 2 seeds, until 1.5 s after a warmup of 0.5 s, three observables)."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "gas.toml").write_text(scene)
    keys = {
        "scene": '"gas.toml"',
        "until": "1.5",
        "warmup": "0.5",
        "seeds": "2",
        "observables": '["compressibility", "collision_rate", "energy.dissipated_J"]',
    }
    for line in head.strip().splitlines():
        key, value = line.split("=", 1)
        keys[key.strip()] = value.strip()
    text = "[sweep]\n" + "".join(f"{k} = {v}\n" for k, v in keys.items())
    path = folder / "sweep.toml"
    path.write_text(text + "\n[parameters]\n" + parameters + "\n")
    return path
