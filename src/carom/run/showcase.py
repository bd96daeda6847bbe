"""The showcase behind ``make demo``: the two-sphere study and a few scenes of both engines
(spheres, event-driven; rigid bodies in 2D and 3D, time-stepped), on one page.

:func:`build_showcase` writes, into one output directory (all or nothing)::

    index.html          every figure, film and table below, linked and shown
    cases/              the seven-case study: cases.csv, cases.json, case-1.png ... case-7.png
    scenes/NAME/        each scene's carom run: animation, plots, summary, events, trajectory
    sweeps/NAME/        each sweep's carom sweep on a local Dask cluster: table and plots
"""

from __future__ import annotations

import contextlib
import html
import json
import multiprocessing
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from carom import __version__
from carom.io.outdir import check_output, staged_output
from carom.jit import kernels_cached, usable_cpus
from carom.run.runner import RunReport, run_scene
from carom.run.study import write_case_study
from carom.scene import find_scene, load_scene
from carom.studies.two_spheres import CASES, MODELS, run_study
from carom.sweeps import SweepSpec, load_sweep, sweep
from carom.sweeps.plots import series

__all__ = ["SHOWCASE_SCENES", "SHOWCASE_SWEEPS", "build_showcase"]

#: the scenes shown, in page order: the event-driven engine's, then the rigid engine's in 2D
#: and in 3D
SHOWCASE_SCENES = (
    *(f"case-{case.number}" for case in CASES),
    "newtons-cradle",
    "billiards-break",
    "hard-sphere-gas",
    "rod-drop",
    "card-house",
    "pyramid",
    "tumbler",
    "pyramid-3d",
    "ring-toss",
    "billiards-3d",
    "three-cushion",
)
#: the parameter sweeps shown (carom sweep, on a local Dask cluster: the sweep extra)
SHOWCASE_SWEEPS = ("eos-2d",)


def build_showcase(
    out: Path,
    *,
    force: bool = False,
    scenes: tuple[str, ...] = SHOWCASE_SCENES,
    sweeps: tuple[str, ...] = SHOWCASE_SWEEPS,
    say: Callable[[str], object] = print,
) -> Path:
    """Run the study and ``scenes``; write them and ``index.html`` to ``out``.

    Parameters
    ----------
    out : Path
        The output directory (replaced only with ``force``).
    force : bool
        Replace a non-empty ``out``.
    scenes : tuple of str
        Built-in scene names or scene files to run.
    sweeps : tuple of str
        Built-in sweep names or sweep files to run (skipped, with a note, without Dask).
    say : callable
        Receives one line per step done.

    Returns
    -------
    Path
        ``out / "index.html"``.
    """
    check_output(out, force=force)
    for scene in scenes:
        find_scene(scene)  # a bad name fails before anything runs
    specs = [load_sweep(name) for name in sweeps]
    if specs and not _have_dask():
        say("(the sweeps are skipped: they run on Dask: pip install 'carom[sweep]')")
        specs = []
    with staged_output(out, force=force) as staging, contextlib.ExitStack() as pools:
        # the scenes start first: on two cores their kernels compile while the study runs
        ran = _start_scenes(scenes, staging / "scenes", pools)
        cases = staging / "cases"
        cases.mkdir()
        records = run_study()
        write_case_study(cases, records)
        say(f"the seven two-sphere cases: {len(records)} impacts -> {out / 'cases'}/")
        shown: list[tuple[str, Path, list[str]]] = []
        if not kernels_cached():
            say("compiling the engines' kernels (once per install; a minute or two) ...")
        for scene, folder, report in ran:
            if report.prepare_seconds >= 1.0 and not shown:
                say(
                    f"(the engine's kernels: compiled or loaded in {report.prepare_seconds:.1f} "
                    f"s, once per install; not counted in the run times)"
                )
            say(f"{report.title}: {report.work()} -> {out / 'scenes' / folder.name}/")
            shown.append((scene, folder, report.written))
        swept: list[tuple[SweepSpec, Path, list[str]]] = []
        for spec in specs:
            folder = staging / "sweeps" / spec.name
            done = sweep(spec, folder, progress=False)
            say(
                f"{spec.title}: {done.runs} runs on {done.workers} Dask workers in "
                f"{done.wall_seconds:.1f} s -> {out / 'sweeps' / folder.name}/"
            )
            swept.append((spec, folder, done.written))
        page = _page(staging, json.loads((cases / "cases.json").read_text()), shown, swept)
        (staging / "index.html").write_text(page, encoding="utf-8")
    return out / "index.html"


#: what a group of the showcase's scenes costs on a cold cache [s], by the plug that builds
#: their engine: its kernels compiled (measured alone on 2 cores: the 3D rigid engine's 86 s,
#: the 2D one's 49 s, the event-driven one's 11 s) and about 4 s a scene, its film included
#: (17 scenes in 65 s, warm, one after the other)
COLD_SECONDS = {
    "carom.engines.rigid3d.assemble": 86.0,
    "carom.engines.rigid.assemble": 49.0,
    "carom.engines.edmd.assemble": 11.0,
}
SCENE_SECONDS = 4.0


def _cold_seconds(group: str, scenes: int) -> float:
    return COLD_SECONDS.get(group, 30.0) + SCENE_SECONDS * scenes


def _start_scenes(
    scenes: tuple[str, ...], folder: Path, pools: contextlib.ExitStack
) -> Iterator[tuple[str, Path, RunReport]]:
    """Start running each scene into ``folder / NAME``; the iterator yields it, its folder and
    its report, in the order given. On two cores or more the scenes run now, in two processes
    (shut down with ``pools``: on an error the scenes not started are dropped), each taking
    whole groups of scenes whose engine one plug builds (the event-driven engine in 2D and 3D
    alike, the rigid one per dimension), so that each compiles those kernels once and the two
    compile side by side; the groups go to the lane with less work so far, largest first
    (:data:`COLD_SECONDS`). A scene's files are the same bits whichever process ran it."""
    folders = {scene: folder / Path(scene).stem for scene in scenes}
    groups: dict[str, list[str]] = {}
    for scene in scenes:
        world = load_scene(find_scene(scene)).build(engine=False)  # (nothing compiles)
        groups.setdefault(world.engine_entry.plugs[world.dim], []).append(scene)
    lanes: list[list[str]] = [[], []]
    work = [0.0, 0.0]
    for key in sorted(groups, key=lambda k: -_cold_seconds(k, len(groups[k]))):
        emptier = int(work[1] < work[0])
        lanes[emptier] += groups[key]
        work[emptier] += _cold_seconds(key, len(groups[key]))
    if usable_cpus() < 2 or not lanes[1]:
        return (
            (scene, folders[scene], run_scene(scene, folders[scene], progress=False))
            for scene in scenes
        )
    spawn = multiprocessing.get_context("spawn")  # (no fork of a process with threads)
    futures = {}
    for lane in lanes:
        pool = ProcessPoolExecutor(1, mp_context=spawn)
        pools.callback(pool.shutdown, wait=True, cancel_futures=True)
        for scene in lane:
            futures[scene] = pool.submit(run_scene, scene, folders[scene], progress=False)
    return ((scene, folders[scene], futures[scene].result()) for scene in scenes)


_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 1100px; margin: 2em auto; padding: 0 1em;
       color: #222; line-height: 1.45; }
h1 { margin-bottom: 0.2em; } h2 { margin-top: 2.2em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.92em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; }
th { background: #f3f3f3; } td.text, th.text { text-align: left; }
.good { color: #1a7f37; } .bad { color: #b42318; }
.scene { margin: 1.5em 0 2.5em; } .row { display: flex; flex-wrap: wrap; gap: 1em; }
.row img { max-width: 520px; width: 100%; border: 1px solid #eee; }
video { max-width: 100%; border: 1px solid #ddd; } nav a { margin-right: 1em; }
.files a { margin-right: 0.8em; font-family: monospace; }
"""


def _have_dask() -> bool:
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


def _page(
    root: Path,
    study: dict[str, Any],
    shown: list[tuple[str, Path, list[str]]],
    swept: list[tuple[SweepSpec, Path, list[str]]],
) -> str:
    parts = [
        "<!doctype html>",
        '<html lang="en"><head><meta charset="utf-8">',
        "<title>carom showcase</title>",
        f"<style>{_STYLE}</style></head><body>",
        "<h1>carom showcase</h1>",
        f"<p>carom {html.escape(__version__)}: exact, impulse-based collision response. "
        "Everything on this page was computed by <code>make demo</code> "
        "(<code>carom showcase</code>); each figure links to its file.</p>",
        '<nav><a href="#cases">two-sphere study</a><a href="#scenes">scenes</a>'
        + ('<a href="#sweeps">sweeps</a>' if swept else "")
        + "</nav>",
        *_study_section(study),
        '<h2 id="scenes">Scenes</h2>',
        "<p>Each scene was run by <code>carom run</code>: the film of its frames, its energy "
        "and momentum against time, the collision rate, and its summary. The files are "
        "beside each one (trajectory.h5 is H5MD, read by OVITO and MDAnalysis; "
        "<code>carom view</code> replays it in the rerun viewer).</p>",
    ]
    for scene, folder, written in shown:
        parts += _scene_section(root, scene, folder, written)
    if swept:
        parts += [
            '<h2 id="sweeps">Parameter sweeps</h2>',
            "<p>Each sweep was run by <code>carom sweep</code>: every point and seed a task on "
            "a local Dask cluster, the observables against the parameter (the mean over the "
            "seeds with its standard error) beside the closed form, and below it the relative "
            "difference. The table has one row per run (docs/sweeps.md).</p>",
        ]
        for spec, folder, written in swept:
            parts += _sweep_section(root, spec, folder, written)
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def _error_cell(error: float | None, round_off: float) -> str:
    if error is None:
        return "<td>-</td>"
    verdict = "good" if error <= round_off else "bad"
    return f'<td class="{verdict}">{error:.2e}</td>'


def _study_section(study: dict[str, Any]) -> list[str]:
    round_off = study["round_off"]
    models = list(MODELS)
    head = "".join(f"<th>{html.escape(MODELS[m])}</th>" for m in models)
    rows = []
    for rec in study["records"]:
        cells = "".join(_error_cell(rec["models"][m]["error"], round_off) for m in models)
        rows.append(
            f"<tr><td>{rec['case']}</td><td class='text'>{html.escape(rec['title'])}</td>"
            f"<td>{rec['e']:g}</td>{cells}</tr>"
        )
    figures = "".join(
        f'<a href="cases/case-{c.number}.png"><img src="cases/case-{c.number}.png" '
        f'alt="case {c.number}"></a>'
        for c in CASES
    )
    findings = "".join(f"<li>{html.escape(line)}</li>" for line in study["conclusions"])
    return [
        '<h2 id="cases">The two-sphere study: carom against Hecker\'s impulse formula</h2>',
        "<p>Seven impacts of two spheres, each at the restitutions listed, computed with "
        "carom's law and with Hecker's formula (with the contact normal, and in its "
        "one-dimensional head-on reading), against the exact answer in rational arithmetic. "
        "The error is the largest velocity error over the approach speed; green: within "
        f"round-off ({round_off:.1e}).</p>",
        f"<table><tr><th>case</th><th class='text'>set-up</th><th>e</th>{head}</tr>",
        *rows,
        "</table>",
        f"<p>Conclusions, derived from these numbers:</p><ul>{findings}</ul>",
        '<p class="files"><a href="cases/cases.csv">cases.csv</a>'
        '<a href="cases/cases.json">cases.json</a></p>',
        f'<div class="row">{figures}</div>',
    ]


def _scene_section(root: Path, scene: str, folder: Path, written: list[str]) -> list[str]:
    meta = load_scene(find_scene(scene)).scene
    rel = folder.relative_to(root).as_posix()
    title = html.escape(meta.get("title") or folder.name)
    parts = [f'<div class="scene" id="{html.escape(folder.name)}"><h3>{title}</h3>']
    if meta.get("description"):
        parts.append(f"<p>{html.escape(meta['description'])}</p>")
    if "animation.mp4" in written:
        parts.append(
            f'<video controls loop muted preload="metadata" width="720" '
            f'src="{rel}/animation.mp4"></video>'
        )
    elif "animation.gif" in written:
        parts.append(f'<img src="{rel}/animation.gif" alt="animation">')
    if "replay.html" in written:
        parts.append(
            f'<p><a href="{rel}/replay.html">interactive replay</a>: scrub the timeline, '
            "orbit in 3D, click a body for its speed and energy (opens from the file)</p>"
        )
    parts.append(_figures(rel, written))
    summary = json.loads((folder / "summary.json").read_text())
    energy = summary["energy"]
    # the rigid engine's solver, or the event-driven engine's parting floor
    key = "given_by_solver_J" if "given_by_solver_J" in energy else "given_by_parting_floor_J"
    giver = "solver" if key == "given_by_solver_J" else "parting floor"
    facts = [
        ("bodies", summary["bodies"]),
        ("simulated time [s]", summary["simulated_time_s"]),
        ("collisions (pairs, walls)", f"{summary['collisions']}, {summary['wall_collisions']}"),
        ("energy dissipated [J]", f"{energy['dissipated_J']:.6g}"),
        ("rotational kinetic energy at the end [J]", f"{energy['rotational_end_J']:.3g}"),
        (f"energy given by the {giver} [J]", f"{energy[key]:.3g}"),
        ("energy balance error (relative)", f"{energy['balance_error_relative']:.2e}"),
        ("wall time [s]", f"{summary['performance']['wall_time_s']:.3g}"),
    ]
    parts.append(
        "<table>"
        + "".join(f"<tr><th class='text'>{k}</th><td>{v}</td></tr>" for k, v in facts)
        + "</table>"
    )
    parts.append(_files(rel, written))
    return parts


def _sweep_section(root: Path, spec: SweepSpec, folder: Path, written: list[str]) -> list[str]:
    from carom.sweeps.observe import OBSERVABLES, has_theory
    from carom.sweeps.spec import parameter_label

    rel = folder.relative_to(root).as_posix()
    parts = [f'<div class="scene" id="sweep-{html.escape(spec.name)}">']
    parts.append(f"<h3>{html.escape(spec.title)}</h3>")
    if spec.description:
        parts.append(f"<p>{html.escape(spec.description)}</p>")
    parts.append(_figures(rel, written))
    x_name = parameter_label(next(iter(spec.parameters))) if spec.parameters else "point"
    for name in spec.observables:
        if not has_theory(name):
            continue
        observable = OBSERVABLES[name]
        for label, (x, mean, error, _, theory) in series(folder, spec, name).items():
            dim = int(spec.base.get("world", {}).get("dimension", 3))
            assert observable.theory_name is not None
            head = (
                f"<tr><th>{html.escape(x_name)}</th><th>{html.escape(name)} (carom)</th>"
                f"<th>standard error</th><th>{html.escape(observable.theory_name(dim))}</th>"
                "<th>relative difference</th></tr>"
            )
            spread = ["-" if np.isnan(e) else f"{e:.2g}" for e in error]  # (one seed: none)
            rows = "".join(
                f"<tr class='sweep'><td>{a:g}</td><td>{m:.5g}</td><td>{e}</td><td>{t:.5g}</td>"
                f"<td>{m / t - 1:+.2%}</td></tr>"
                for a, m, e, t in zip(x, mean, spread, theory, strict=True)
            )
            caption = f"<caption>{html.escape(label)}</caption>" if label else ""
            parts.append(f"<table>{caption}{head}{rows}</table>")
    parts.append(_files(rel, written))
    return parts


def _figures(rel: str, written: list[str]) -> str:
    """A row of the PNG figures among ``written`` (in folder ``rel``), each linking to itself."""
    images = [name for name in written if name.endswith(".png")]
    links = "".join(f'<a href="{rel}/{n}"><img src="{rel}/{n}" alt="{n}"></a>' for n in images)
    return f'<div class="row">{links}</div>'


def _files(rel: str, written: list[str]) -> str:
    """A line of links to every file written, closing the section."""
    links = "".join(f'<a href="{rel}/{n}">{n}</a>' for n in written)
    return f'<p class="files">{links}</p></div>'
