"""The showcase behind ``make demo``: the two-sphere study and a few scenes of both engines
(spheres, event-driven; rigid bodies, time-stepped), on one page.

:func:`build_showcase` writes, into one output directory (all or nothing)::

    index.html          every figure, film and table below, linked and shown
    cases/              the seven-case study: cases.csv, cases.json, case-1.png ... case-7.png
    scenes/NAME/        each scene's carom run: animation, plots, summary, events, trajectory
"""

from __future__ import annotations

import html
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from carom import __version__
from carom.io.outdir import check_output, staged_output
from carom.jit import kernels_cached
from carom.run.runner import run_scene
from carom.run.study import write_case_study
from carom.scene import find_scene, load_scene
from carom.studies.two_spheres import CASES, MODELS, run_study

__all__ = ["SHOWCASE_SCENES", "build_showcase"]

#: the scenes shown, in page order: the event-driven engine's, then the rigid engine's
SHOWCASE_SCENES = (
    *(f"case-{case.number}" for case in CASES),
    "newtons-cradle",
    "billiards-break",
    "hard-sphere-gas",
    "rod-drop",
    "card-house",
    "pyramid",
    "tumbler",
)


def build_showcase(
    out: Path,
    *,
    force: bool = False,
    scenes: tuple[str, ...] = SHOWCASE_SCENES,
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
    with staged_output(out, force=force) as staging:
        cases = staging / "cases"
        cases.mkdir()
        records = run_study()
        write_case_study(cases, records)
        say(f"the seven two-sphere cases: {len(records)} impacts -> {out / 'cases'}/")
        shown: list[tuple[str, Path, list[str]]] = []
        if not kernels_cached():
            say("compiling the engine's kernels (once per install; about a minute) ...")
        for scene in scenes:
            folder = staging / "scenes" / Path(scene).stem
            report = run_scene(scene, folder, progress=False)
            if report.prepare_seconds >= 1.0 and not shown:
                say(
                    f"(the engine's kernels: compiled or loaded in {report.prepare_seconds:.1f} "
                    f"s, once per install; not counted in the run times)"
                )
            say(f"{report.title}: {report.work()} -> {out / 'scenes' / folder.name}/")
            shown.append((scene, folder, report.written))
        page = _page(staging, json.loads((cases / "cases.json").read_text()), shown)
        (staging / "index.html").write_text(page, encoding="utf-8")
    return out / "index.html"


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


def _page(root: Path, study: dict[str, Any], shown: list[tuple[str, Path, list[str]]]) -> str:
    parts = [
        "<!doctype html>",
        '<html lang="en"><head><meta charset="utf-8">',
        "<title>carom showcase</title>",
        f"<style>{_STYLE}</style></head><body>",
        "<h1>carom showcase</h1>",
        f"<p>carom {html.escape(__version__)}: exact, impulse-based collision response. "
        "Everything on this page was computed by <code>make demo</code> "
        "(<code>carom showcase</code>); each figure links to its file.</p>",
        '<nav><a href="#cases">two-sphere study</a><a href="#scenes">scenes</a></nav>',
        *_study_section(study),
        '<h2 id="scenes">Scenes</h2>',
        "<p>Each scene was run by <code>carom run</code>: the film of its frames, its energy "
        "and momentum against time, the collision rate, and its summary. The files are "
        "beside each one (trajectory.h5 is H5MD, read by OVITO and MDAnalysis; "
        "<code>carom view</code> replays it in the rerun viewer).</p>",
    ]
    for scene, folder, written in shown:
        parts += _scene_section(root, scene, folder, written)
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
    images = [name for name in written if name.endswith(".png")]
    parts.append(
        '<div class="row">'
        + "".join(f'<a href="{rel}/{n}"><img src="{rel}/{n}" alt="{n}"></a>' for n in images)
        + "</div>"
    )
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
    links = "".join(f'<a href="{rel}/{n}">{n}</a>' for n in written)
    parts.append(f'<p class="files">{links}</p></div>')
    return parts
