"""Observables (carom.observables): temperature and pressure are those of the gas's own
motion, whatever its spin or drift (regression: spinning and drifting gases gave Z = 1.95 and
2.37 where 1.04 is right; rough spheres 1.99)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.observables import (
    angular_momentum,
    kinetic_energy,
    rotational_energy,
    rotational_temperature,
    temperature,
)
from carom.scene.layouts import lattice_gas

PHI = 0.01
# Carnahan-Starling, PHYSICS.md section 6: Z = (1 + phi + phi^2 - phi^3) / (1 - phi)^3
Z_CS = (1 + PHI + PHI**2 - PHI**3) / (1 - PHI) ** 3


def _gas(*, spin: bool = False, drift: float = 0.0, rough: bool = False) -> carom.World:
    """1331 unit spheres, phi = 0.01, kT = 1, periodic; optionally spinning at the rotational
    temperature 1, drifting along x at ``drift`` m/s, or perfectly rough (e = 1, beta = 1)."""
    base = lattice_gas(3, 11, PHI, seed=4)
    world = carom.World(3, base.box, "periodic")
    v = base.velocities + np.array([drift, 0.0, 0.0])
    w = None
    if spin or rough:
        # each component Gaussian with variance T / I, I = 2/5 m a^2 = 0.1 (m = 1, a = 0.5)
        w = np.random.default_rng(5).normal(scale=math.sqrt(1.0 / 0.1), size=(base.n_bodies, 3))
    material = carom.Material(1.0, beta=1.0) if rough else carom.Material(1.0)
    world.add_spheres(base.positions, v, radius=0.5, material=material, angular_velocities=w)
    return world


def _z(world: carom.World) -> float:
    world.run(until=20.0)  # the lattice melts; contacts reach their equilibrium frequency
    world.stats.reset()
    world.run(until=420.0)
    stats = world.stats
    rho = world.n_bodies / float(np.prod(world.box))
    return stats.pressure / (rho * stats.temperature)


@pytest.mark.needs_jit
def test_pressure_counts_neither_spin_nor_drift() -> None:
    still, spinning = _gas(), _gas(spin=True)
    z_still, z_spin = _z(still), _z(spinning)
    # smooth spheres: spins never enter the dynamics, so the two runs have the same collisions
    # and the same translational motion: the same Z to round-off
    assert still.stats.collisions == spinning.stats.collisions
    assert z_spin == pytest.approx(z_still, rel=1e-12)
    # against Carnahan-Starling: the virial part Z - 1 = 0.04 comes from C ~ 3.7e4 collisions,
    # each J . r with a relative spread of about 1/2, so its error is about
    # 0.04 * 0.5 / sqrt(3.7e4) = 1e-4; 6e-4 is six of those
    assert still.stats.collisions > 30_000
    assert z_still == pytest.approx(Z_CS, abs=6e-4)
    # Galilean invariance: a gas moving at 2 m/s as a whole has the same pressure (its own
    # collisions differ from the still gas's by round-off amplified over the run, so the
    # statistical tolerance above applies)
    assert _z(_gas(drift=2.0)) == pytest.approx(Z_CS, abs=6e-4)


@pytest.mark.needs_jit
def test_rough_spheres_have_the_hard_sphere_equation_of_state() -> None:
    # e = 1, beta = 1 (perfectly rough): the normal impulse is the smooth one, and at
    # equilibrium (rotational temperature = translational) the positions and translational
    # velocities are those of smooth hard spheres: Z is Carnahan-Starling's. The kinetic part
    # uses the translational temperature at the end of the window, which now fluctuates as
    # energy passes to and from rotation: its share of a fixed total over 6N quadratic terms
    # has a relative spread 1 / sqrt(3N + 1) = 0.016, so Z - 1 = 0.041 is known to
    # 0.041 * 0.016 = 6.5e-4; 3.5e-3 is five of those (the smooth gas's 1e-4 adds little)
    rough = _gas(rough=True)
    assert _z(rough) == pytest.approx(Z_CS, abs=3.5e-3)
    # equipartition: T_rot = T; each is a mean over 1331 bodies of a chi-squared with three
    # degrees of freedom over 3 (relative spread sqrt(2/3) / sqrt(1331) = 0.022), so their
    # ratio is within 5 x sqrt(2) x 0.022 = 0.16 of 1
    assert rough.stats.rotational_temperature == pytest.approx(rough.stats.temperature, rel=0.16)
    # and energy is kept: e = 1, beta = 1 conserve translational plus rotational energy
    assert rough.stats.energy_lost == pytest.approx(0.0, abs=1e-9 * rough.stats.kinetic_energy)


def test_temperature_of_a_drifting_gas_is_that_of_the_gas_at_rest() -> None:
    # T = sum m |v - v_cm|^2 / (d N): adding one velocity to every body changes nothing
    # but round-off in v - v_cm (|v| ~ 3, eps ~ 2e-16)
    still, moving = _gas(), _gas(drift=2.0)
    t_still = temperature(still.bodies, still.velocities)
    assert temperature(moving.bodies, moving.velocities) == pytest.approx(t_still, rel=1e-13)
    # kinetic energy does include the drift: 1/2 N m u^2 more (velocities have zero mean)
    ke_still = kinetic_energy(still.bodies, still.velocities, still.angular_velocities)
    ke_moving = kinetic_energy(moving.bodies, moving.velocities, moving.angular_velocities)
    assert ke_moving - ke_still == pytest.approx(0.5 * still.n_bodies * 2.0**2, rel=1e-12)


def test_rotational_temperature_closed_form() -> None:
    # two disks (2D: one rotational degree of freedom), I = 1/2 m a^2: m = 2, a = 0.1 gives
    # I = 0.01 kg m^2; spins 3 and -5 rad/s: T_rot = (0.01 * 9 + 0.01 * 25) / (1 * 2) = 0.17 J
    world = carom.World(2, [1.0, 1.0])
    world.add_spheres(
        [[0.25, 0.5], [0.75, 0.5]], radius=0.1, mass=2.0, angular_velocities=[3.0, -5.0]
    )
    t_rot = rotational_temperature(world.bodies, world.angular_velocities)
    assert t_rot == pytest.approx(0.17, rel=4 * 2.2e-16)  # a few products and one sum
    assert world.stats.rotational_temperature == t_rot


def test_rotational_energy_and_angular_momentum_closed_forms() -> None:
    # The two disks above (I = 0.01 kg m^2 each, m = 2) at (0.25, 0.5) and (0.75, 0.5) with
    # velocities (1, 0) and (0, -2), spins 3 and -5 rad/s:
    #   rotational energy = (0.01 * 9 + 0.01 * 25) / 2 = 0.17 J
    #   L_z = sum m (x v_y - y v_x) + I w
    #       = 2 (0 - 0.5 * 1) + 2 (0.75 * -2 - 0) + 0.01 * 3 + 0.01 * -5 = -4.02 kg m^2/s
    # and a static body adds nothing to either.
    world = carom.World(2, [1.0, 1.0])
    world.add_spheres(
        [[0.25, 0.5], [0.75, 0.5]],
        [[1.0, 0.0], [0.0, -2.0]],
        radius=0.1,
        mass=2.0,
        angular_velocities=[3.0, -5.0],
    )
    world.add_static_spheres([[0.5, 0.9]], radius=0.05)
    b, w = world.bodies, world.angular_velocities
    assert rotational_energy(b, w) == pytest.approx(0.17, rel=4 * 2.2e-16)
    lz = angular_momentum(b, world.positions, world.velocities, w)
    assert lz[:2].tolist() == [0.0, 0.0]
    assert lz[2] == pytest.approx(-4.02, rel=8 * 2.2e-16)  # six products, five sums
    # 3D: one sphere (I = 2/5 m a^2 = 0.4 * 1 * 0.25 = 0.1) at (1, 2, 3) with v = (0, 0, 1) and
    # w = (1, 0, 0): x × v = (2, -1, 0), so L = (2 + 0.1, -1, 0)
    world3 = carom.World(3, [4.0, 4.0, 4.0])
    world3.add_spheres(
        [[1.0, 2.0, 3.0]], [[0.0, 0.0, 1.0]], radius=0.5, angular_velocities=[[1.0, 0, 0]]
    )
    l3 = angular_momentum(
        world3.bodies, world3.positions, world3.velocities, world3.angular_velocities
    )
    np.testing.assert_allclose(l3, [2.1, -1.0, 0.0], rtol=4 * 2.2e-16, atol=0)
