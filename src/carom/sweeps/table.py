"""The results table of a sweep: ``results.csv`` written row by row as points finish, read
back to resume, and put in order at the end; ``results.parquet`` beside it when pyarrow is
installed.

One row per point and seed. Columns: ``point`` (from 0), ``seed`` (empty: the scene's own),
one per parameter (its dotted path; lists as JSON), ``status`` (``ok`` or ``failed``), one
per observable, ``<observable>_theory`` where carom knows a closed form (empty where it does
not apply to the point), and ``message`` (why a point failed). Numbers are written in full
(``repr``): the file reads back to the same bits, and the same sweep with the same seeds
writes the same file, byte for byte, however many workers ran it.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path
from typing import Any

from carom.errors import CaromError
from carom.io.outdir import write_whole
from carom.sweeps.observe import has_theory
from carom.sweeps.spec import Point, SweepSpec, show_value

__all__ = ["RESULTS", "ResultsTable", "columns", "completed", "write_parquet"]

RESULTS = "results.csv"
PARQUET = "results.parquet"


def columns(spec: SweepSpec) -> list[str]:
    """The table's header for ``spec``."""
    head = ["point", "seed", *spec.parameters, "status"]
    for name in spec.observables:
        head.append(name)
        if has_theory(name):
            head.append(f"{name}_theory")
    return [*head, "message"]


def _cell(value: float | None) -> str:
    return "" if value is None else repr(float(value))


def completed(folder: Path, spec: SweepSpec) -> set[tuple[int, int | None]]:
    """The (point, seed) of every successful row of the table in ``folder`` (read only)."""
    path = folder / RESULTS
    if not path.exists():
        return set()
    header = columns(spec)
    status = header.index("status")
    return {_key(row) for row in _read(path, header) if row[status] == "ok"}


class ResultsTable:
    """``results.csv`` in a sweep's folder: rows appended (and forced to disk) as they come.

    Parameters
    ----------
    folder : Path
        The sweep's output folder.
    spec : SweepSpec
        The sweep (its columns).
    keep : bool
        Keep the rows of an interrupted sweep that succeeded (``--resume``); the failed ones
        are dropped, to be run again. Otherwise the table starts empty.
    """

    def __init__(self, folder: Path, spec: SweepSpec, *, keep: bool) -> None:
        self.path = folder / RESULTS
        self.header = columns(spec)
        self.spec = spec
        self.rows: dict[tuple[int, int | None], list[str]] = {}
        if keep and self.path.exists():
            for row in _read(self.path, self.header):
                if row[self.header.index("status")] == "ok":
                    self.rows[_key(row)] = row
        self._rewrite()
        self.file = self.path.open("a", newline="", encoding="utf-8")
        self.writer = csv.writer(self.file, lineterminator="\n")

    def done(self) -> set[tuple[int, int | None]]:
        """The (point, seed) of every row that succeeded."""
        return set(self.rows)

    def add(self, point: Point, result: dict[str, Any]) -> None:
        """Append the row of a finished point and force it to disk."""
        row = [str(point.index), "" if point.seed is None else str(point.seed)]
        row += [show_value(point.values[p]) for p in self.spec.parameters]
        row.append(result["status"])
        for name in self.spec.observables:
            row.append(_cell(result["values"].get(name)))
            if has_theory(name):
                row.append(_cell(result["theory"].get(name)))
        row.append(result["message"])
        self.writer.writerow(row)
        self.file.flush()
        os.fsync(self.file.fileno())
        self.rows[point.key] = row

    def close(self) -> None:
        self.file.close()

    def finish(self) -> None:
        """Close the file and write it again in the order of the points (atomically)."""
        self.close()
        self._rewrite()

    def _rewrite(self) -> None:
        """Write the header and the rows, in order, to a new file that replaces the old."""
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(self.header)
        for key in sorted(self.rows, key=lambda k: (k[0], -1 if k[1] is None else k[1])):
            writer.writerow(self.rows[key])
        write_whole(self.path, buffer.getvalue())


def _read(path: Path, header: list[str]) -> list[list[str]]:
    """The complete rows of an existing table (a line cut short by a crash is dropped)."""
    text = path.read_text(encoding="utf-8")
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]  # the row being written when it stopped
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return []
    if rows[0] != header:
        raise CaromError(
            f"{path} has other columns than this sweep writes ({', '.join(rows[0])}); it "
            f"belongs to another sweep: pass --force to start again, or choose another --out"
        )
    return [r for r in rows[1:] if len(r) == len(header)]


def _key(row: list[str]) -> tuple[int, int | None]:
    return (int(row[0]), None if row[1] == "" else int(row[1]))


def write_parquet(folder: Path, spec: SweepSpec) -> bool:
    """``results.parquet`` from ``results.csv`` when pyarrow is installed (observables as
    float64, with nulls where the CSV is empty); False when it is not."""
    try:
        import pyarrow as pa
        import pyarrow.csv as pacsv
        import pyarrow.parquet as pq
    except ImportError:
        return False
    numeric = {"point": pa.int64(), "seed": pa.int64(), "status": pa.string()}
    for name in spec.observables:
        numeric[name] = pa.float64()
        if has_theory(name):
            numeric[f"{name}_theory"] = pa.float64()
    numeric["message"] = pa.string()
    table = pacsv.read_csv(
        folder / RESULTS,
        convert_options=pacsv.ConvertOptions(column_types=numeric, strings_can_be_null=False),
    )
    temporary = folder / f".{PARQUET}.tmp"
    pq.write_table(table, temporary)
    temporary.replace(folder / PARQUET)
    return True
