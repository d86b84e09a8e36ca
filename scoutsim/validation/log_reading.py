"""Reading experiment logs: :func:`load_log` (one CSV, CSV.gz or Parquet file, checked by
:mod:`scoutsim.validation.log_checks`) and :func:`load_dataset` (several files, or
directories of them, every problem reported at once).
"""

from __future__ import annotations

import gzip
import io
import json
from pathlib import Path

import numpy as np

from .experiment_log import ExperimentLog
from .log_checks import check_columns, validate_values
from .log_format import COLUMN_UNITS, LOG_SUFFIXES, PARQUET_META_KEY, LogError, log_suffix, row_text

__all__ = ["load_log", "load_dataset"]


def _parse_meta_value(text: str):
    text = text.strip()
    try:
        return json.loads(text)
    except ValueError:
        return text


def _read_csv(path: Path):
    """(header names, list of row-string-lists, metadata, line number of the header)."""
    opener = gzip.open if log_suffix(path) == ".csv.gz" else open
    try:
        with opener(path, "rt", encoding="utf-8", newline="") as fh:
            text = fh.read()
    except (OSError, EOFError) as exc:
        raise LogError(f"{path}: cannot read the file: {exc}", path) from None
    except UnicodeDecodeError as exc:
        raise LogError(f"{path}: not UTF-8 text ({exc})", path) from None
    lines = text.splitlines()
    meta, i = {}, 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        body = lines[i].lstrip("#").strip()
        if "=" in body:
            k, v = body.split("=", 1)
            meta[k.strip()] = _parse_meta_value(v)
        i += 1
    if i >= len(lines):
        raise LogError(f"{path}: no header line (the file is empty)", path)
    header_line = i + 1
    names = [n.strip() for n in lines[i].split(",")]
    import csv as _csv

    rows = list(_csv.reader(io.StringIO("\n".join(lines[i + 1 :]))))
    return names, rows, meta, header_line


def _read_parquet(path: Path):
    try:
        import pyarrow.parquet as pq
    except ImportError:
        raise LogError(
            f"{path}: reading Parquet logs needs the optional dependency pyarrow; "
            "install it with `pip install pyarrow` (or `pip install "
            "scoutsim[parquet]`), or convert the log to CSV",
            path,
        ) from None
    try:
        table = pq.read_table(path)
    except Exception as exc:  # pyarrow raises several types
        raise LogError(f"{path}: cannot read the Parquet file: {exc}", path) from None
    meta = {}
    raw = (table.schema.metadata or {}).get(PARQUET_META_KEY)
    if raw:
        meta = json.loads(raw.decode("utf-8"))
    names = list(table.column_names)
    cols = {}
    for n in names:
        col = table.column(n).to_pylist()
        cols[n] = col
    return names, cols, meta


def load_log(path, *, repair_spikes: bool = False) -> ExperimentLog:
    """Read and validate one log (CSV, CSV.gz or Parquet; see the module docstring).

    ``repair_spikes``: replace each isolated spike (:func:`isolated_spikes`) by the median
    of its neighbours instead of refusing the log; the replacements are listed in
    ``log.repairs``.

    Raises
    ------
    LogError
        With a message naming the file, the column and the row of the first problem.
    """
    path = Path(path)
    if not path.exists():
        raise LogError(f"{path}: log file not found", path)
    if not path.is_file():
        raise LogError(f"{path}: not a file", path)
    suffix = log_suffix(path)
    if suffix in (".parquet", ".pq"):
        names, raw, meta = _read_parquet(path)
        check_columns(path, names)
        cols = {}
        for n in names:
            try:
                cols[n] = np.array([np.nan if v is None else v for v in raw[n]], dtype=float)
            except (TypeError, ValueError):
                vals = raw[n]
                k = next(
                    i
                    for i, v in enumerate(vals)
                    if v is not None and not isinstance(v, (int, float))
                )
                if n in COLUMN_UNITS:
                    raise LogError(
                        f"{path}: column '{n}', row {k + 1}: {vals[k]!r} is not a number",
                        path,
                        n,
                        k + 1,
                    ) from None
        header_line = None
    elif suffix in (".csv", ".csv.gz"):
        names, rows, meta, header_line = _read_csv(path)
        check_columns(path, names)
        ncol = len(names)
        data = np.full((len(rows), ncol), np.nan)
        for i, r in enumerate(rows):
            if len(r) != ncol:
                if len(r) == 0 or (len(r) == 1 and not r[0].strip()):
                    raise LogError(
                        f"{path}: {row_text(i + 1, header_line)} is empty", path, None, i + 1
                    )
                raise LogError(
                    f"{path}: {row_text(i + 1, header_line)} has {len(r)} "
                    f"fields, the header has {ncol}",
                    path,
                    None,
                    i + 1,
                )
            for j, cell in enumerate(r):
                cell = cell.strip()
                if cell == "" or cell.lower() in ("nan", "na"):
                    continue
                try:
                    data[i, j] = float(cell)
                except ValueError:
                    if names[j] in COLUMN_UNITS:
                        raise LogError(
                            f"{path}: column '{names[j]}', "
                            f"{row_text(i + 1, header_line)}: {cell!r} is not a "
                            "number",
                            path,
                            names[j],
                            i + 1,
                        ) from None
        cols = {n: data[:, j] for j, n in enumerate(names)}
    else:
        raise LogError(
            f"{path}: unknown log format '{suffix or path.name}'; use {', '.join(LOG_SUFFIXES)}",
            path,
        )
    repairs: list | None = [] if repair_spikes else None
    validate_values(path, cols, header_line, repairs)
    return ExperimentLog(columns=cols, meta=meta, path=str(path), repairs=tuple(repairs or ()))


def _expand(paths) -> list[Path]:
    if isinstance(paths, (str, Path)):
        paths = [paths]
    out = []
    for p in paths:
        p = Path(p)
        if p.is_dir():
            found = sorted(f for f in p.iterdir() if f.is_file() and log_suffix(f) in LOG_SUFFIXES)
            if not found:
                raise LogError(f"{p}: directory holds no log files ({', '.join(LOG_SUFFIXES)})", p)
            out.extend(found)
        else:
            out.append(p)
    return out


def load_dataset(paths, *, repair_spikes: bool = False) -> list[ExperimentLog]:
    """Load several runs (files, or directories of log files). Every file is checked; if any
    is bad, one LogError lists all the problems, one per line (``repair_spikes``: as
    :func:`load_log`)."""
    logs, problems = [], []
    for p in _expand(paths):
        try:
            logs.append(load_log(p, repair_spikes=repair_spikes))
        except LogError as exc:
            problems.append(exc)
    if problems:
        if len(problems) == 1:
            raise problems[0]
        first = problems[0]
        raise LogError(
            f"{len(problems)} bad log file(s):\n" + "\n".join(f"  {e}" for e in problems),
            first.path,
            first.column,
            first.row,
        )
    if not logs:
        raise LogError("no log files given")
    return logs
