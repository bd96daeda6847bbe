"""A comparison as a terminal table, ``compare.json`` and ``compare.png``."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from carom.compare.driver import Comparison, RigidComparison

__all__ = ["format_number", "format_table", "plot_comparison", "write_comparison"]

#: colours per engine, the same in every plot
COLOURS = {
    "carom": "#d62728",
    "pymunk": "#1f77b4",
    "pybullet": "#2ca02c",
    "mujoco": "#9467bd",
    "box2d": "#ff7f0e",
}
#: where a zero is drawn on a log axis
FLOOR = 1e-17


def format_number(x: float | None, digits: int = 2) -> str:
    """``x`` in e-notation; "-" for None (not measured), "0" for an exact zero."""
    if x is None:
        return "-"
    if x == 0.0:
        return "0"
    return f"{x:.{digits}e}"


def _bodies(n: int) -> str:
    return "1 body" if n == 1 else f"{n} bodies"


def _to_carom(engines: dict[str, dict[str, Any]], run: dict[str, Any]) -> str:
    """A run's wall time over carom's, or "-" when carom did not run (or took no time)."""
    carom = engines.get("carom")
    if carom is None or carom["wall_s"] <= 0:
        return "-"
    return f"{run['wall_s'] / carom['wall_s']:.3g}"


def format_table(comparison: Comparison | RigidComparison) -> str:
    """The comparison as a fixed-width table, one row per engine."""
    if isinstance(comparison, RigidComparison):
        return format_rigid_table(comparison)
    spec = comparison.scene
    source = comparison.expected.source if comparison.expected is not None else "none"
    lines = [
        f"{spec.name}: {_bodies(spec.n)}, {spec.dim}D, {spec.until:g} s simulated",
        f"closed form: {source}",
        "",
        f"{'engine':<9} {'version':<8} {'dt [s]':>9} {'velocity err':>12} {'energy err':>10} "
        f"{'max pen./r':>10} {'tunnelled':>9} {'wall [s]':>9} {'/ carom':>8}",
    ]
    for name, run in comparison.engines.items():
        m = run["metrics"]
        ratio = _to_carom(comparison.engines, run)
        dt = "events" if name == "carom" else f"{run['dt_s']:.4g}"
        velocity, energy, depth = (
            format_number(m[k])
            for k in ("velocity_error", "energy_error", "max_penetration_per_radius")
        )
        lines.append(
            f"{name:<9} {run['version']:<8} {dt:>9} {velocity:>12} {energy:>10} {depth:>10} "
            f"{'yes' if m['tunnelled'] else 'no':>9} {run['wall_s']:>9.3g} {ratio:>8}"
        )
    for name, why in comparison.skipped.items():
        lines.append(f"{name:<9} skipped: {why}")
    lines += [
        "",
        "velocity err: max |v - v_exact| / speed scale at the closed form's check times; energy "
        "err: (E - E_exact) / E0; max pen./r: deepest overlap (pairs and walls) / smallest "
        "radius; wall: time inside the engine's step calls, and its ratio to carom's",
    ]
    return "\n".join(lines)


def format_rigid_table(comparison: RigidComparison) -> str:
    """A rigid comparison as a fixed-width table, one row per engine (a scene with joints
    adds the joint gap and the error against the joints' closed forms)."""
    spec = comparison.scene
    check = comparison.expected
    jointed = spec.joint_ints.shape[0] > 0
    forms = [check.source] if check is not None else []
    if jointed:
        from carom.compare.jointed import JointGauge

        said = JointGauge(spec).source
        forms += [said] if said else []
    head = (
        f"{'engine':<9} {'version':<8} {'Hz':>5} {'v err':>8} {'w err':>8} {'E gained':>8} "
        f"{'overlap':>8} {'through':>7} {'top moved':>9} {'max turn':>8} "
    )
    if jointed:
        head += f"{'joint gap':>9} {'form err':>8} "
    lines = [
        f"{spec.name}: {_bodies(spec.n)}, {spec.dim}D rigid, {spec.until:g} s simulated "
        f"(carom at {1.0 / spec.dt:g} Hz)",
        f"closed form: {'; '.join(forms) if forms else 'none'}",
        "",
        head + f"{'ms/step':>8} {'/ carom':>7}",
    ]
    for name, run in comparison.engines.items():
        m = run["metrics"]
        ratio = _to_carom(comparison.engines, run)
        row = (
            f"{name:<9} {run['version']:<8} {1.0 / run['dt_s']:>5.4g} "
            f"{format_number(m['velocity_error']):>8} "
            f"{format_number(m['omega_error']):>8} {format_number(m['energy_gain']):>8} "
            f"{format_number(m['max_overlap_m']):>8} {m['bodies_through_static']:>7} "
            f"{m['top_drift_m']:>8.3g}m {m['max_rotation_deg']:>7.3g}° "
        )
        if jointed:
            row += f"{format_number(m['joint_gap_m']):>8}m {format_number(m['joint_error']):>8} "
        lines.append(row + f"{run['ms_per_step']:>8.3g} {ratio:>7}")
    for name, why in comparison.skipped.items():
        lines.append(f"{name:<9} skipped: {why}")
    held = {n: r["metrics"].get("reference") for n, r in comparison.engines.items()}
    held = {n: ref for n, ref in held.items() if ref is not None and n != ref["engine"]}
    if held:
        first = next(iter(held.values()))
        lines += [
            "",
            f"against {first['engine']}, state by state to {first['until_s']:g} s (its first "
            "ball-cushion event, if any, ends the comparison):",
        ]
        for name, ref in held.items():
            lines.append(
                f"{name:<9} position {ref['position_m']:.2g} m, velocity "
                f"{ref['velocity_m_s']:.2g} m/s, angular velocity {ref['omega_rad_s']:.2g} rad/s"
            )
    joints = (
        "joint gap: the largest break of any joint over the run [m] (a pin's anchors apart, a "
        "rod's length off, a rope past its length, a slider off its axis); form err: the "
        "largest relative error against the joints' closed forms (a lone pendulum's period; "
        "the cradle's |1 - out| and the others' speed, over the strike speed); "
        if jointed
        else ""
    )
    lines += [
        "",
        "Hz: the engine's steps per second; v err, w err: |v - v_exact| and |w - w_exact| x "
        "reach, over the contact point's approach speed, after the impact; E gained: "
        "largest rise of kinetic plus potential energy over E(0); overlap: deepest overlap "
        "seen [m] (carom's exact geometry on each engine's poses); through: bodies whose "
        "centre crossed a static body; top moved: the highest body's distance from its start "
        f"at the end; max turn: largest rotation of any body; {joints}ms/step: time inside "
        "the step calls per step; / carom: time inside the step calls "
        "for the whole run over carom's (the same simulated time)",
    ]
    return "\n".join(lines)


def plot_rigid(comparison: RigidComparison, path: Path) -> None:
    """Energies, angular momentum and overlap over time; top drift and ms per step."""
    from carom.viz import require_matplotlib

    require_matplotlib()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5), constrained_layout=True)
    names = list(comparison.engines)
    colours = [COLOURS.get(n, "0.4") for n in names]
    (energy_ax, momentum_ax), (overlap_ax, time_ax) = axes
    for name, colour in zip(names, colours, strict=True):
        series = comparison.engines[name]["series"]
        t = series["time"]
        energy_ax.plot(t, series["translation"], color=colour, lw=1.4, label=f"{name} translation")
        energy_ax.plot(
            t, series["rotation"], color=colour, lw=1.0, ls="--", label=f"{name} rotation"
        )
        momentum_ax.plot(t, series["angular_momentum"], color=colour, lw=1.2, label=name)
        points = [(a, b) for a, b in zip(t, series["overlap"], strict=True) if b == b]
        overlap_ax.plot(
            [a for a, _ in points],
            [max(b, FLOOR) for _, b in points],
            color=colour,
            lw=1.2,
            label=name,
        )
    energy_ax.set(xlabel="time [s]", ylabel="[J]", title="kinetic energy: translation, rotation")
    energy_ax.legend(fontsize=7)
    momentum_ax.set(
        xlabel="time [s]",
        ylabel="[kg m^2/s]",
        title="angular momentum about the origin"
        + (" (magnitude)" if comparison.scene.dim == 3 else ""),
    )
    momentum_ax.legend(fontsize=8)
    overlap_ax.set(
        xlabel="time [s]", ylabel="[m]", yscale="log", title="deepest overlap (0 drawn at 1e-17)"
    )
    time_ax.bar(names, [comparison.engines[n]["ms_per_step"] for n in names], color=colours)
    time_ax.set(title="time per step", ylabel="ms")
    for k, n in enumerate(names):
        m = comparison.engines[n]["metrics"]
        time_ax.text(
            k,
            comparison.engines[n]["ms_per_step"],
            f"{comparison.engines[n]['ms_per_step']:.3g} ms\ntop moved {m['top_drift_m']:.2g} m",
            ha="center",
            va="bottom",
            fontsize=8,
        )
    dim = comparison.scene.dim
    fig.suptitle(f"{comparison.title}: {_bodies(comparison.scene.n)}, {dim}D rigid", fontsize=12)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_comparison(comparison: Comparison | RigidComparison, path: Path) -> None:
    """Energy and penetration over time, velocity error and wall time per engine."""
    if isinstance(comparison, RigidComparison):
        plot_rigid(comparison, path)
        return
    from carom.viz import require_matplotlib

    require_matplotlib()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5), constrained_layout=True)
    spec = comparison.scene
    names = list(comparison.engines)
    colours = [COLOURS.get(n, "0.4") for n in names]
    (energy_ax, pen_ax), (vel_ax, time_ax) = axes
    for name, colour in zip(names, colours, strict=True):
        series = comparison.engines[name]["series"]
        on_top = 3 if name == "carom" else 2
        e0 = series["energy"][0]
        energy_ax.plot(
            series["time"],
            [e / e0 for e in series["energy"]],
            color=colour,
            lw=1.4,
            label=name,
            zorder=on_top,
        )
        pen = [max(p / float(spec.radius.min()), FLOOR) for p in series["penetration"]]
        pen_ax.plot(series["time"], pen, color=colour, lw=1.2, label=name, zorder=on_top)
    energy_ax.set(xlabel="time [s]", ylabel="E / E(0)", title="total energy")
    energy_ax.legend(fontsize=8)
    pen_ax.set(
        xlabel="time [s]",
        ylabel="deepest overlap / radius",
        yscale="log",
        title="penetration (zero drawn at 1e-17)",
    )

    def bars(ax: Any, values: list[float | None], title: str, unit: str) -> None:
        shown = [FLOOR if v is None or v == 0.0 else abs(v) for v in values]
        ax.bar(names, shown, color=colours)
        ax.set(yscale="log", title=title, ylabel=unit)
        for k, v in enumerate(values):
            text = "n/a" if v is None else ("0" if v == 0.0 else f"{abs(v):.1e}")
            ax.text(k, shown[k], text, ha="center", va="bottom", fontsize=8)

    velocity = [comparison.engines[n]["metrics"]["velocity_error"] for n in names]
    if any(v is not None for v in velocity):
        bars(vel_ax, velocity, "velocity error vs closed form", "max |v - v_exact| / speed")
    else:  # no velocity closed form (a gas): the energy is the exact answer
        bars(
            vel_ax,
            [comparison.engines[n]["metrics"]["energy_error"] for n in names],
            f"energy error at {spec.until:g} s (exact: conserved)",
            "|E - E(0)| / E(0)",
        )
    bars(
        time_ax,
        [comparison.engines[n]["wall_s"] for n in names],
        f"wall time for {spec.until:g} s simulated",
        "s",
    )
    fig.suptitle(f"{comparison.title}: {_bodies(spec.n)}, {spec.dim}D", fontsize=12)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_comparison(
    comparison: Comparison | RigidComparison, folder: Path, *, plot: bool = True
) -> list[str]:
    """Write ``compare.json``, ``compare.txt`` and (with matplotlib) ``compare.png``."""
    folder.mkdir(parents=True, exist_ok=True)
    data = comparison.to_json()
    (folder / "compare.json").write_text(
        json.dumps(_jsonable(data), indent=2, allow_nan=False) + "\n"
    )
    (folder / "compare.txt").write_text(format_table(comparison) + "\n")
    written = ["compare.json", "compare.txt"]
    if plot:
        plot_comparison(comparison, folder / "compare.png")
        written.append("compare.png")
    return written


def _jsonable(value: Any) -> Any:
    """``value`` with numpy arrays and numbers as lists and floats, and non-finite floats as
    strings ("inf"), so that the file is strict JSON."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if hasattr(value, "tolist"):
        return _jsonable(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return value
