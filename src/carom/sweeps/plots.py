"""The figures of a sweep: each observable against the parameter, the mean over the seeds
with its standard error, and the closed form where carom knows it."""

from __future__ import annotations

import csv
import json
import math
from collections import defaultdict
from pathlib import Path

import numpy as np

from carom.sweeps.observe import OBSERVABLES, has_theory
from carom.sweeps.spec import SweepSpec, parameter_label
from carom.sweeps.table import RESULTS

__all__ = ["series", "write_plots"]


def _number(text: str) -> float | None:
    try:
        value = json.loads(text)
    except ValueError:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value)


def series(
    folder: Path, spec: SweepSpec, name: str
) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """An observable's curves from ``results.csv`` (its finite values): for each setting of
    the parameters after the first (a label), ``(x, mean, standard error, seeds, theory)``
    over the first parameter's values (the point's number when it has none, or its values
    are not numbers).
    The standard error is ``std / sqrt(n)`` over the seeds (NaN for one seed); theory is the
    mean closed form of the point (NaN where there is none)."""
    with (folder / RESULTS).open(newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    parameters = list(spec.parameters)
    first = parameters[0] if parameters else None
    numeric = first is not None and all(_number(r[first]) is not None for r in rows)
    groups: dict[str, dict[float, tuple[list[float], list[float]]]] = defaultdict(dict)
    for row in rows:
        if row["status"] != "ok" or row[name] == "" or not math.isfinite(float(row[name])):
            continue  # (NaN: the observable does not apply, e.g. a pressure under gravity)
        x = _number(row[first]) if numeric and first is not None else float(row["point"])
        assert x is not None
        # crossed: a curve per setting of the other parameters; zipped, they move together
        others = parameters[1:] if spec.combine == "cross" else []
        label = ", ".join(f"{parameter_label(p)} = {row[p]}" for p in others)
        values, theory = groups[label].setdefault(x, ([], []))
        values.append(float(row[name]))
        cell = row.get(f"{name}_theory", "")
        if cell:
            theory.append(float(cell))
    out = {}
    for label, points in groups.items():
        xs = np.array(sorted(points))
        mean, error, count, closed = [], [], [], []
        for x in xs:
            values, theory = points[float(x)]
            v = np.array(values)
            mean.append(float(np.mean(v)))
            error.append(float(np.std(v, ddof=1) / math.sqrt(len(v))) if len(v) > 1 else math.nan)
            count.append(len(v))
            closed.append(float(np.mean(theory)) if theory else math.nan)
        out[label] = (xs, np.array(mean), np.array(error), np.array(count), np.array(closed))
    return out


def write_plots(folder: Path, spec: SweepSpec) -> list[str]:
    """Write ``plot-<observable>.png`` for each observable with a value; return the names."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dim = int(spec.base.get("world", {}).get("dimension", 3))
    parameters = list(spec.parameters)
    written = []
    for name in spec.observables:
        curves = series(folder, spec, name)
        if not curves:
            continue
        observable = OBSERVABLES.get(name)
        closed = has_theory(name) and any(np.any(np.isfinite(c[4])) for c in curves.values())
        if closed:
            fig, (ax, low) = plt.subplots(
                2, 1, figsize=(7, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]}
            )
        else:
            fig, ax = plt.subplots(figsize=(7, 4.5))
        for k, (label, (x, mean, error, count, theory)) in enumerate(sorted(curves.items())):
            colour = f"C{k % 10}"
            seeds = int(np.max(count))
            measured = f"carom ({seeds} seed{'s' if seeds > 1 else ''}, mean ± s.e.)"
            bars = None if np.all(np.isnan(error)) else error
            ax.errorbar(
                x,
                mean,
                yerr=bars,
                fmt="o",
                color=colour,
                capsize=3,
                label=f"{label}: {measured}" if label else measured,
            )
            ok = np.isfinite(theory)
            if closed and np.any(ok):
                assert observable is not None and observable.theory_name is not None
                ax.plot(
                    x[ok],
                    theory[ok],
                    ".-",
                    color=colour,
                    lw=1.2,
                    alpha=0.8,
                    label=observable.theory_name(dim) + (f" ({label})" if label else ""),
                )
                # below: how far the measurement is from the closed form, relative
                low.errorbar(
                    x[ok],
                    mean[ok] / theory[ok] - 1,
                    yerr=None if bars is None else error[ok] / np.abs(theory[ok]),
                    fmt="o",
                    color=colour,
                    capsize=3,
                )
        if closed:
            assert observable is not None and observable.theory_name is not None
            low.axhline(0.0, color="k", lw=0.8)
            low.set_ylabel(f"relative to\n{observable.theory_name(dim)}", fontsize=8)
            low.grid(alpha=0.3)
        xs = np.concatenate([c[0] for c in curves.values()])
        if parameters and np.all(xs > 0) and np.max(xs) / np.min(xs) > 50:
            ax.set_xscale("log")
        (low if closed else ax).set_xlabel(
            parameter_label(parameters[0]) if parameters else "point"
        )
        if observable is not None:
            unit = f" [{observable.unit}]" if observable.unit != "-" else ""
            ax.set_ylabel(f"{observable.what}{unit}", fontsize=9)
        else:
            ax.set_ylabel(f"{name} (summary.json)", fontsize=9)
        ax.set_title(spec.title, fontsize=11)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = f"plot-{name.replace('.', '-')}.png"
        fig.savefig(folder / path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written
