"""Rows on disk: a journal written as rows arrive, the final table written atomically.

While a sweep runs, every finished row is appended (and fsynced) to a journal beside the
output, ``.<name>.rows.jsonl``: a sweep that is killed, or whose worker dies, keeps every
finished row there. At the end the table (CSV, or Parquet for a ``.parquet`` output) is
written atomically and the journal removed. ``--resume`` reads the journal and an existing
table and skips the runs they hold.
"""
from __future__ import annotations

import csv
import io
import json
import math
import os
from pathlib import Path
from typing import Any, Iterable, TextIO

from pymunk_bot.outcomes.results import write_atomic

FORMATS = (".csv", ".parquet")


def check_output(path: Path) -> None:
    """Refuse an output the sweep could not write, before anything runs (ValueError)."""
    if path.suffix.lower() not in FORMATS:
        raise ValueError(f"{path}: the output must end in .csv or .parquet")
    if path.suffix.lower() == ".parquet":
        _pyarrow()
    if not path.parent.exists() and str(path.parent):
        raise ValueError(f"{path}: the directory {path.parent} does not exist")
    if path.is_dir():
        raise ValueError(f"{path}: is a directory")


def journal_path(path: Path) -> Path:
    return path.with_name(f".{path.name}.rows.jsonl")


class Journal:
    """Append-only JSON lines, flushed and fsynced per batch of rows; the file is created with
    the first row, so a sweep that fails before any run finishes leaves nothing behind."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._file: TextIO | None = None  # opened by the first write

    def write(self, rows: Iterable[dict]) -> None:
        if self._file is None:
            self._file = open(self.path, "a", encoding="utf-8")
        for row in rows:
            self._file.write(json.dumps(row, allow_nan=True) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        if self._file is not None:
            self._file.close()


def read_journal(path: Path) -> list[dict]:
    """Rows of a journal; a last line cut short by a crash is ignored."""
    if not path.exists():
        return []
    rows = []
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            rows.append(json.loads(line))
        except json.JSONDecodeError:
            break
    return rows


def read_table(path: Path) -> list[dict]:
    """Rows of a finished table written by :func:`write_table` (types restored)."""
    if not path.exists():
        return []
    if path.suffix.lower() == ".parquet":
        return _pyarrow().parquet.read_table(path).to_pylist()
    with open(path, newline="", encoding="utf-8") as f:
        return [{k: _cell_value(v) for k, v in row.items()} for row in csv.DictReader(f)]


def columns_of(rows: list[dict]) -> list[str]:
    """Every key, in first-seen order (robots' fields may differ between runs)."""
    seen: dict[str, None] = {}
    for row in rows:
        for key in row:
            seen.setdefault(key, None)
    return list(seen)


def write_table(path: Path, rows: list[dict]) -> None:
    """The whole table, sorted by run index, written atomically."""
    rows = sorted(rows, key=lambda r: r["run"])
    columns = columns_of(rows)
    if path.suffix.lower() == ".parquet":
        pa = _pyarrow()
        table = pa.table({c: [r.get(c) for r in rows] for c in columns})
        sink = pa.BufferOutputStream()
        pa.parquet.write_table(table, sink)
        write_atomic(path, sink.getvalue().to_pybytes())
        return
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: _cell_text(row.get(k)) for k in columns})
    write_atomic(path, text.getvalue().encode("utf-8"))


def _cell_text(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)  # round-trips exactly
    return str(value)


def _cell_value(text: str) -> Any:
    """Back from CSV text: '' -> None, True/False, int, float, else the string."""
    if text == "":
        return None
    if text in ("True", "False"):
        return text == "True"
    for kind in (int, float):
        try:
            value = kind(text)
        except ValueError:
            continue
        return value if kind is int or math.isfinite(value) or text in ("nan", "inf", "-inf") \
            else text
    return text


def _pyarrow():
    try:
        import pyarrow
        import pyarrow.parquet  # noqa: F401  (loads the submodule)
    except ImportError:
        raise ValueError("Parquet output needs pyarrow: pip install 'pymunk-bot[parquet]' "
                         "(or write .csv)") from None
    return pyarrow
