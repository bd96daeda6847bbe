"""The rigid-body engine's isolated impacts against closed forms (issue 13, items 3 and 4).

An isolated impact is solved at its time of impact, so its outcome must be Newton's
restitution at the contact point with the bodies' inertia (Hecker's formula), whatever the
step. The closed forms are derived in each test from the impulse ``j`` along ``n`` at offset
``r`` from the centre of mass:

    v' = v + j n / m,   omega' = omega + (r x n) j / I,
    j = -(1 + e) u_n / (1/m_A + 1/m_B + (r_A x n)^2/I_A + (r_B x n)^2/I_B)   (Hecker 1997)

with ``u_n`` the normal speed of the contact points before the impact. Tolerances: the
impulse is a few dozen float64 operations on O(1) numbers (1e-12 relative), except where the
test reads the time of impact found by conservative advancement (to 1e-9 of the bodies'
size), noted where used.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from carom.bodies import BODY_KINDS
from carom.engines.rigid.driver import RigidEngine
from carom.engines.rigid.model import build_model, new_state
from carom.engines.stepped.settings import RigidSettings
from carom.shapes import Box, Circle, Polygon, Shape2D
from tests.conftest import JIT_DISABLED

G = 9.81
REL = 1e-12


def engine(
    bodies: list[
        tuple[Shape2D, str, float, tuple[float, float], tuple[float, float], float, float]
    ],
    *,
    e: float = 1.0,
    mu: float = 0.0,
    gravity: tuple[float, float] = (0.0, -G),
    **options: object,
) -> RigidEngine:
    """An engine of (shape, kind, mass, position, velocity, angle, omega) bodies, one material."""
    pieces, kinds, masses, inertias, x, v, angle, omega = [], [], [], [], [], [], [], []
    for shape, kind, mass, position, velocity, theta, spin in bodies:
        pieces.append(shape.pieces())
        kinds.append(BODY_KINDS[kind])
        if kind == "dynamic":
            props = shape.mass_properties(mass=mass)
            masses.append(props.mass)
            inertias.append(props.inertia)
        else:
            masses.append(math.inf)
            inertias.append(math.inf)
        x.append(position)
        v.append(velocity)
        angle.append(theta)
        omega.append(spin)
    model = build_model(
        pieces,
        np.array(kinds),
        np.array(masses),
        np.array(inertias),
        np.zeros(len(bodies), int),
        np.array([[e]]),
        np.array([[mu]]),
        np.array(gravity, float),
    )
    state = new_state(
        model, np.array(x, float), np.array(v, float), np.array(angle), np.array(omega)
    )
    return RigidEngine(model, state, RigidSettings(**options))  # type: ignore[arg-type]


def run_logged(eng: RigidEngine, until: float, *, first: bool = False) -> np.ndarray:
    """The impacts solved exactly up to ``until`` [s]; with ``first``, stop at the end of the
    step of the first one."""
    records: list[np.ndarray] = []
    while eng.time < until - 1e-12 and not (first and records):
        eng.step(records.append)
    return np.concatenate(records) if records else np.zeros(0)


GROUND = (Box(20.0, 1.0), "static", math.inf, (0.0, -0.5), (0.0, 0.0), 0.0, 0.0)


@pytest.mark.parametrize("degrees", [10.0, 30.0, 60.0])
@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("rate", [60.0, 240.0])
def test_rod_dropped_at_an_angle(degrees: float, e: float, rate: float) -> None:
    # A 1 m x 2 cm rod at angle theta falls from rest and lands on its lowest corner. Before
    # the impact it does not turn, so every point moves at the centre's speed v0 = -u_n; the
    # floor's normal is (0, 1) and r x n = r_x, the corner's horizontal offset. Then
    # j = (1 + e) v0 / (1/m + r_x^2/I), and after: v_y = -v0 + j/m, omega = r_x j / I.
    length, width, m = 1.0, 0.02, 1.3
    theta = math.radians(degrees)
    rod = Box(length, width)
    inertia = m * (length**2 + width**2) / 12.0
    drop = length / 2 * math.sin(theta) + width / 2 * math.cos(theta)
    eng = engine(
        [(rod, "dynamic", m, (0.0, drop + 0.4), (0, 0), theta, 0.0), GROUND], e=e, rate=rate
    )
    first = run_logged(eng, 1.0, first=True)[0]
    c, s = math.cos(theta), math.sin(theta)
    r_x = -length / 2 * c + width / 2 * s  # the corner (-L/2, -w/2), turned by theta
    v0 = -first["un_before"]
    j = (1.0 + e) * v0 / (1.0 / m + r_x**2 / inertia)
    assert math.isclose(first["impulse"][1], j, rel_tol=REL)
    assert abs(first["impulse"][0]) < REL * j
    assert math.isclose(first["un_after"], e * v0, rel_tol=REL, abs_tol=REL)
    # the time of impact: free fall through the 0.4 m gap (CA to 1e-9 of 1 m)
    assert abs(first["time"] - math.sqrt(2 * 0.4 / G)) < 1e-8
    if e > 0.0:
        # the end of the impact's step: the rod flew on under gravity from the impact
        _, v, _, w = eng.sample()
        late = eng.time - first["time"]
        assert math.isclose(v[0, 1] + G * late, -v0 + j / m, rel_tol=REL, abs_tol=1e-12)
        assert math.isclose(w[0, 2], r_x * j / inertia, rel_tol=REL)


@pytest.mark.parametrize("rate", [60.0, 150.0])
def test_box_landing_flat_rebounds_with_e_v_and_no_spin(rate: float) -> None:
    # Both bottom corners touch together; by symmetry the two normal impulses are equal and
    # the 2x2 complementarity problem gives v' = e v0, omega' = 0.
    e = 0.6
    box = Box(1.0, 0.5)
    eng = engine(
        [(box, "dynamic", 2.0, (0.3, 0.25 + 1.0), (0, 0), 0.0, 0.0), GROUND], e=e, rate=rate
    )
    first = run_logged(eng, 1.0, first=True)[0]
    v0 = -first["un_before"]
    _, v, _, w = eng.sample()
    late = eng.time - first["time"]
    assert math.isclose(v[0, 1] + G * late, e * v0, rel_tol=REL)
    assert abs(v[0, 0]) < 1e-15
    assert abs(w[0, 2]) < 1e-12
    assert math.isclose(first["impulse"][1], 2.0 * (1 + e) * v0, rel_tol=REL)


def test_two_polygons_in_free_flight_conserve_momenta() -> None:
    # A pentagon and a box meet off-centre with spins, no gravity, e = 0.7, frictionless.
    # Linear momentum and angular momentum about the origin are conserved by any internal
    # impulse; the kinetic energy lost by one frictionless point impact is
    # (1 - e^2) u_n^2 / (2 K), K = 1/m_A + 1/m_B + (r_A x n)^2/I_A + (r_B x n)^2/I_B.
    e = 0.7
    pent, box = Polygon.regular(5, 0.4), Box(0.6, 0.3)
    bodies = [
        (pent, "dynamic", 1.5, (-1.0, 0.12), (2.0, 0.1), 0.3, 1.5),
        (box, "dynamic", 0.8, (1.0, -0.05), (-1.5, 0.0), -0.2, -0.7),
    ]
    eng = engine(bodies, e=e, gravity=(0.0, 0.0))
    m = np.array([1.5, 0.8])
    inertia = np.array(
        [pent.mass_properties(mass=1.5).inertia, box.mass_properties(mass=0.8).inertia]
    )

    def momenta() -> tuple[np.ndarray, float, float]:
        x, v, _, w = eng.sample()
        p = (m[:, None] * v).sum(axis=0)
        lz = float(np.sum(m * (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0]) + inertia * w[:, 2]))
        ke = float(np.sum(0.5 * m * (v**2).sum(axis=1) + 0.5 * inertia * w[:, 2] ** 2))
        return p, lz, ke

    p0, l0, ke0 = momenta()
    x0, v0, _, _ = eng.sample()
    hits = run_logged(eng, 1.0)
    assert hits.size == 1
    hit = hits[0]
    p1, l1, ke1 = momenta()
    assert np.allclose(p1, p0, rtol=0, atol=1e-13)
    assert abs(l1 - l0) < 1e-13
    # K at the time of impact: both bodies flew straight, so x(t) = x0 + v0 t
    xa = x0 + v0 * hit["time"]
    point = hit["point"][:2]
    n = hit["impulse"][:2] / np.linalg.norm(hit["impulse"][:2])
    cross = [(point - xa[i])[0] * n[1] - (point - xa[i])[1] * n[0] for i in range(2)]
    k = 1 / m[0] + 1 / m[1] + cross[0] ** 2 / inertia[0] + cross[1] ** 2 / inertia[1]
    lost = (1 - e**2) * hit["un_before"] ** 2 / (2 * k)
    assert math.isclose(ke0 - ke1, lost, rel_tol=1e-10)


@pytest.mark.parametrize(("spin", "mu", "regime"), [(2.0, 0.9, "stick"), (40.0, 0.2, "slide")])
def test_spinning_disk_hits_a_wall_with_friction(spin: float, mu: float, regime: str) -> None:
    # A disk (radius R, I = m R^2/2) moving at (u, w) into a wall on its right, normal
    # n = (-1, 0), spinning at omega. At the contact r = (R, 0): normal speed u_n = -u,
    # tangential (t = (n_y, -n_x) = (0, 1)) speed u_t = w + omega R. The normal and tangent
    # rows decouple (r is along n): K_nn = 1/m, K_tt = 1/m + R^2/I = 3/m.
    # Newton: j_n = (1 + e) m u. Sticking: j_t = -m u_t / 3 if |j_t| <= mu j_n; else
    # sliding: j_t = -mu j_n sign(u_t). After: v = (u - j_n/m, w + j_t/m),
    # omega' = omega + (r x j)/I = omega + R j_t / I.
    m, radius, e = 2.0, 0.25, 0.8
    u, w = 3.0, 0.5
    inertia = m * radius**2 / 2
    wall = (Box(0.2, 4.0), "static", math.inf, (1.1, 0.0), (0, 0), 0.0, 0.0)
    disk = (Circle(radius), "dynamic", m, (0.0, 0.0), (u, w), 0.0, spin)
    eng = engine([disk, wall], e=e, mu=mu, gravity=(0.0, 0.0))
    hit = run_logged(eng, 1.0, first=True)[0]
    jn = (1 + e) * m * u
    ut = w + spin * radius
    jt = -m * ut / 3.0
    if regime == "slide":
        assert abs(jt) > mu * jn
        jt = -mu * jn * math.copysign(1.0, ut)
    else:
        assert abs(jt) <= mu * jn
    _, v, _, omega = eng.sample()
    assert math.isclose(v[0, 0], u - jn / m, rel_tol=REL)
    assert math.isclose(v[0, 1], w + jt / m, rel_tol=REL)
    assert math.isclose(omega[0, 2], spin + radius * jt / inertia, rel_tol=REL)
    assert np.allclose(hit["impulse"][:2], [-jn, jt], rtol=REL)


def test_fast_box_never_passes_a_thin_wall() -> None:
    # A 5 cm box at 100 m/s moves 1.7 m a step at 60 Hz, 33 times its size, against a 1 cm
    # wall. Twenty shots, each starting a random fraction of a step further back: every one
    # must rebound from the wall's near face (x = 0), never reach beyond it.
    rng = np.random.default_rng(7)
    for phase in rng.uniform(0.0, 1.0, 20):
        start = -3.0 - phase * 100.0 / 60.0
        bullet = (Box(0.05, 0.05), "dynamic", 0.1, (start, 0.0), (100.0, 0.0), 0.0, 0.0)
        wall = (Box(0.01, 2.0), "static", math.inf, (0.005, 0.0), (0, 0), 0.0, 0.0)
        eng = engine([bullet, wall], e=0.5, gravity=(0.0, 0.0))
        eng.advance(0.2, 10**9, None)
        x, v, _, _ = eng.sample()
        assert x[0, 0] < -0.025, f"phase {phase}: the box went through, x = {x[0, 0]}"
        assert math.isclose(v[0, 0], -50.0, rel_tol=1e-12)


def test_fast_bodies_meet_head_on() -> None:
    # two 5 cm boxes at +-200 m/s, 1 m apart: they meet after 2.5 ms, within the first step,
    # and exchange velocities (equal masses, e = 1)
    a = (Box(0.05, 0.05), "dynamic", 0.1, (-0.5, 0.0), (200.0, 0.0), 0.0, 0.0)
    b = (Box(0.05, 0.05), "dynamic", 0.1, (0.5, 0.0), (-200.0, 0.0), 0.0, 0.0)
    eng = engine([a, b], e=1.0, gravity=(0.0, 0.0))
    hits = run_logged(eng, 1 / 60)
    assert hits.size == 1
    assert abs(hits[0]["time"] - 0.95 / 400.0) < 1e-12
    _, v, _, _ = eng.sample()
    assert np.allclose(v, [[-200.0, 0.0], [200.0, 0.0]], rtol=1e-12)


# (as plain Python, NUMBA_DISABLE_JIT=1, a few examples cover the kernels' code: each is 60
# steps of islands solved exactly, a minute of plain Python)
@settings(max_examples=3 if JIT_DISABLED else 25, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.floats(0.0, 1.0),
    st.floats(0.0, 1.0),
)
def test_energy_never_gained_in_free_flight(seed: int, e: float, mu: float) -> None:
    # Six bodies of mixed shapes fly in a closed box of static walls, no gravity, e <= 1: no
    # impact law or solver stage may add kinetic energy (round-off allowance 1e-9 relative).
    rng = np.random.default_rng(seed)
    shapes = [Circle(0.2), Box(0.4, 0.2), Polygon.regular(5, 0.25), Box(0.3, 0.3, radius=0.05)]
    bodies = []
    for k in range(6):
        shape = shapes[k % len(shapes)]
        position = (-1.5 + (k % 3) * 1.5, -0.8 + (k // 3) * 1.6)
        velocity = tuple(rng.uniform(-4, 4, 2))
        bodies.append(
            (shape, "dynamic", 1.0, position, velocity, rng.uniform(-3, 3), rng.uniform(-5, 5))
        )
    for centre, size in (
        ((0, -2.5), (6.0, 1.0)),
        ((0, 2.5), (6.0, 1.0)),
        ((-3.0, 0), (1.0, 6.0)),
        ((3.0, 0), (1.0, 6.0)),
    ):
        bodies.append((Box(*size), "static", math.inf, centre, (0, 0), 0.0, 0.0))
    eng = engine(bodies, e=e, mu=mu, gravity=(0.0, 0.0))
    masses = np.array([b[0].mass_properties(mass=1.0).mass for b in bodies[:6]])
    inertia = np.array([b[0].mass_properties(mass=1.0).inertia for b in bodies[:6]])

    def kinetic() -> float:
        _, v, _, w = eng.sample()
        return float(
            np.sum(0.5 * masses * (v[:6] ** 2).sum(axis=1) + 0.5 * inertia * w[:6, 2] ** 2)
        )

    before = kinetic()
    for _ in range(60):
        eng.step()
        assert kinetic() <= before * (1 + 1e-9)


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_a_kinematic_paddle_does_the_work_of_its_impact(e: float) -> None:
    # A kinematic paddle at V = 2 m/s strikes a 1.5 kg disk at rest, head-on, no gravity. In
    # the paddle's frame the disk comes in at V and leaves at e V, so it leaves at (1 + e) V;
    # the impulse on it is j = m (1 + e) V, and the paddle's work is j V = m (1 + e) V^2, of
    # which 1/2 m (1 + e)^2 V^2 is the disk's kinetic energy and 1/2 m (1 - e^2) V^2 is lost.
    # The ledger keeps the work apart: E0 + work = E + lost - given. (A contact with a
    # kinematic body goes to the solver, docs/rigid.md; head-on at one point, its restitution
    # pass gives the closed form.)
    m, speed = 1.5, 2.0
    paddle = (Box(0.2, 2.0), "kinematic", math.inf, (0.0, 0.0), (speed, 0.0), 0.0, 0.0)
    disk = (Circle(0.25), "dynamic", m, (1.0, 0.0), (0.0, 0.0), 0.0, 0.0)
    eng = engine([paddle, disk], e=e, gravity=(0.0, 0.0))
    while eng.time < 1.0 - 1e-12:  # the paddle reaches the disk at 0.325 s
        eng.step()
    _, v, _, w = eng.sample()
    assert v[1, 0] == pytest.approx((1 + e) * speed, rel=REL)
    assert v[1, 1] == 0.0
    assert w[1, 2] == 0.0
    c = eng.counters()
    assert c.work_done == pytest.approx(m * (1 + e) * speed**2, rel=REL)
    assert c.energy_lost == pytest.approx(0.5 * m * (1 - e**2) * speed**2, rel=REL, abs=1e-12)
    assert c.energy_given == 0.0


def test_a_kinematic_lift_feeds_the_ledger_through_the_solver() -> None:
    # A 1 kg box rests on a kinematic platform; the platform rises at V = 0.5 m/s for 2 s
    # (gravity 9.81). The soft solver (a resting contact, not an isolated impact) carries the
    # box up: the platform's work is then at least the box's gain of potential and kinetic
    # energy, m g (y - y0) + 1/2 m v^2, and the ledger closes to round-off.
    speed = 0.5
    lift = (Box(4.0, 0.5), "kinematic", math.inf, (0.0, -0.25), (0.0, speed), 0.0, 0.0)
    box = (Box(0.5, 0.5), "dynamic", 1.0, (0.0, 0.25), (0.0, 0.0), 0.0, 0.0)
    eng = engine([lift, box], e=0.0, mu=0.5)
    x0, _, _, _ = eng.sample()
    while eng.time < 2.0 - 1e-12:
        eng.step()
    x, v, _, _ = eng.sample()
    gain = G * (x[1, 1] - x0[1, 1]) + 0.5 * float(np.sum(v[1] ** 2))
    c = eng.counters()
    assert x[1, 1] - x0[1, 1] == pytest.approx(2.0 * speed, abs=0.01)  # it rode the lift
    assert c.work_done >= gain
    assert c.work_done == pytest.approx(gain + c.energy_lost - c.energy_given, rel=1e-12)
    # the platform moves at V throughout, so its work is V times the impulse it gave, and by
    # the impulse-momentum theorem that impulse is m v_y + m g T: work = V (m v_y + m g T)
    # (= m g V T + m V^2 = 10.06 J once the box rides at V), to round-off
    assert c.work_done == pytest.approx(speed * (v[1, 1] + G * 2.0), rel=1e-12)
