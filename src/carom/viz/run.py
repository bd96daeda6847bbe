"""The figures of a run: energy, momentum and angular momentum against time, the collision
rate, and the speed distribution against Maxwell-Boltzmann."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from carom.observables import RunHistory
from carom.viz import require_matplotlib
from carom.world import World

__all__ = ["write_run_plots"]


def write_run_plots(folder: Path, world: World, history: RunHistory) -> list[str]:
    """Write ``energy.png`` (the energy balance, translational and rotational kinetic energy
    apart when anything spins; momentum; angular momentum about the origin when anything
    turns), ``collision_rate.png`` (when there were collisions) and, for a gas of equal masses
    in a periodic box, ``speeds.png``; return the file names written."""
    require_matplotlib()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    t = np.array(history.time)
    spin = np.array(history.angular_momentum)
    rot = np.array(history.rotational)
    # the angular momentum panel when anything turns (spin, or a rigid body's orbit)
    turning = bool(np.any(rot) or world.engine_entry.turns)
    rows = 3 if turning else 2
    fig, axes = plt.subplots(rows, 1, figsize=(7, 3 * rows), sharex=True)
    top, bottom = axes[0], axes[1]
    ke, pe, lost, given, work = (
        np.array(history.kinetic),
        np.array(history.potential),
        np.array(history.dissipated),
        np.array(history.given),
        np.array(history.work),
    )
    if np.any(rot):
        top.plot(t, ke - rot, label="translational kinetic")
        top.plot(t, rot, label="rotational kinetic")
    else:
        top.plot(t, ke, label="kinetic")
    if np.any(pe):
        top.plot(t, pe, label="potential (gravity)")
    if np.any(lost):
        top.plot(t, lost, label="dissipated")
    if np.any(given):
        source = world.engine_entry.gives_energy
        top.plot(t, given, label=f"given ({source})")
    if np.any(work):
        top.plot(t, work, label="work by kinematic bodies")
        top.plot(t, ke + pe + lost - given - work, "k--", lw=1, label="total less that work (E0)")
    else:
        top.plot(t, ke + pe + lost - given, "k--", lw=1, label="total (conserved)")
    top.set_ylabel("energy [J]")
    top.legend(loc="best", fontsize=8)
    p = np.array(history.momentum)
    for k in range(p.shape[1]):
        bottom.plot(t, p[:, k], label=f"p_{'xyz'[k]}")
    bottom.set_ylabel("momentum [kg m/s]")
    bottom.legend(loc="best", fontsize=8)
    if turning:
        for k in range(3) if world.dim == 3 else (2,):
            axes[2].plot(t, spin[:, k], label=f"L_{'xyz'[k]}")
        axes[2].set_ylabel("angular momentum\nabout the origin [kg m²/s]")
        axes[2].legend(loc="best", fontsize=8)
    axes[-1].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(folder / "energy.png", dpi=110)
    plt.close(fig)
    written.append("energy.png")

    collisions = np.array(history.collisions)
    if t.size > 1 and collisions[-1] > collisions[0]:
        # the rate between successive records: collisions counted over each interval
        fig, ax = plt.subplots(figsize=(7, 3.5))
        rate = np.diff(collisions) / np.diff(t)
        ax.step(t[:-1], rate, where="post")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("collisions per second")
        ax.set_title("collision rate (bodies and walls)")
        fig.tight_layout()
        fig.savefig(folder / "collision_rate.png", dpi=110)
        plt.close(fig)
        written.append("collision_rate.png")

    moving = world.bodies.mobile
    masses = world.masses[moving]
    temperature = world.stats.temperature
    if (
        world.boundary == "periodic"
        and moving.sum() >= 100
        and temperature > 0
        and np.allclose(masses, masses[0])
    ):
        speed = np.linalg.norm(world.velocities[moving], axis=1)
        m, d = masses[0], world.dim
        v = np.linspace(0, speed.max() * 1.1, 200)
        if d == 3:
            density = 4 * np.pi * v**2 * (m / (2 * np.pi * temperature)) ** 1.5
        else:
            density = (m * v / temperature) * 1.0
        density = density * np.exp(-m * v**2 / (2 * temperature))
        fig, ax = plt.subplots(figsize=(7, 3.5))
        ax.hist(speed, bins=40, density=True, alpha=0.6, label=f"speeds at t = {world.time:g} s")
        ax.plot(v, density, "k", label=f"Maxwell-Boltzmann, k_B T = {temperature:.4g} J")
        ax.set_xlabel("speed [m/s]")
        ax.set_ylabel("probability density [s/m]")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(folder / "speeds.png", dpi=110)
        plt.close(fig)
        written.append("speeds.png")
    return written
