"""Named columns on disk: Parquet when pyarrow is installed, gzip-compressed CSV otherwise.

A table is a dict of equal-length 1-D NumPy arrays (float64, integer or string columns)
plus a JSON-safe metadata dict; both formats carry the metadata and each column's unit and
dtype, and read back bit for bit (CSV writes floats with 17 significant digits, which
round-trip exactly):

    path = write_table("out/timeseries", columns, units={"t": "s"}, metadata={...})
    columns, metadata = read_table(path)

Parquet files keep the metadata in the schema (key ``scoutsim``); CSV files start with one
comment line ``# scoutsim: {json}``, then the header ``name [unit],...``.
"""

from __future__ import annotations

import gzip
import importlib.util
import json
import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from .run_directory import PARTIAL_SUFFIX, atomic_write

__all__ = [
    "FORMATS",
    "SUFFIXES",
    "default_format",
    "write_table",
    "read_table",
    "read_metadata",
    "table_path",
    "TableWriter",
    "TableError",
    "write_rows_csv",
    "write_rows_parquet",
]

#: table formats and the suffix of their files
SUFFIXES = {"parquet": ".parquet", "csv": ".csv.gz"}
FORMATS = tuple(SUFFIXES)
_KEY = "scoutsim"


def write_rows_csv(path, columns: dict) -> None:
    """A study's table of rows (named columns of equal length, Python values, None where a
    row has no value) as a plain CSV: a header of the names, then a row each, None empty.
    For study outputs a user reads (sweep, tune); runs use :func:`write_table`."""
    import csv

    names = list(columns)
    n = len(columns[names[0]]) if names else 0
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(names)
        for i in range(n):
            w.writerow(["" if columns[c][i] is None else columns[c][i] for c in names])


def write_rows_parquet(path, columns: dict, install_hint: str = "pip install pyarrow") -> None:
    """The same table as Parquet (needs pyarrow: RuntimeError saying ``install_hint``)."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError as exc:
        raise RuntimeError(f"writing Parquet needs pyarrow: {install_hint}") from exc
    pq.write_table(pa.table(columns), path)


class TableError(ValueError):
    """A file that is not a table written by :func:`write_table` (or is damaged)."""


def default_format() -> str:
    """``"parquet"`` if pyarrow can be imported, else ``"csv"`` (checked without importing
    it)."""
    return "parquet" if importlib.util.find_spec("pyarrow") is not None else "csv"


def table_path(stem, fmt: str) -> Path:
    """``stem`` with the suffix of format ``fmt``."""
    if fmt not in SUFFIXES:
        raise ValueError(f"table format {fmt!r} is not allowed: must be one of {FORMATS}")
    return Path(f"{stem}{SUFFIXES[fmt]}")


def _format_of(path: Path) -> str:
    name = path.name.lower()
    for fmt, suffix in SUFFIXES.items():
        if name.endswith(suffix):
            return fmt
    raise TableError(f"{path}: not a table file (expected {' or '.join(SUFFIXES.values())})")


def write_table(
    stem,
    columns: dict,
    *,
    units: dict | None = None,
    metadata: dict | None = None,
    fmt: str | None = None,
) -> Path:
    """Write ``columns`` (name -> 1-D array, equal lengths) to ``stem`` + the format's
    suffix; ``units`` (name -> unit string) and ``metadata`` (JSON-safe, NaN allowed) are
    stored with it. The file is written whole or not at all
    (:func:`scoutsim.io.run_directory.atomic_write`). Returns the path."""
    fmt = fmt or default_format()
    path = table_path(stem, fmt)
    cols = {n: np.asarray(c) for n, c in columns.items()}
    lengths = {len(c) for c in cols.values()}
    if len(lengths) > 1:
        raise ValueError(f"columns of unequal length: {sorted(lengths)}")
    info = {"columns": _column_info(cols, units), "metadata": metadata or {}}
    writer = _write_parquet if fmt == "parquet" else _write_csv
    return atomic_write(path, lambda tmp: writer(tmp, cols, info))


def _arrow_column(pa, c: np.ndarray):
    """``c`` as an Arrow array built on its buffers (``pa.array`` would import pandas, if
    installed, on its first call: 0.3 s of a short run's command)."""
    if c.dtype.kind == "U":
        data = [x.encode() for x in c.tolist()]
        offsets = np.zeros(len(data) + 1, dtype=np.int32)
        offsets[1:] = np.cumsum([len(d) for d in data])
        return pa.Array.from_buffers(
            pa.string(), len(data), [None, pa.py_buffer(offsets), pa.py_buffer(b"".join(data))]
        )
    if c.dtype.kind == "b":
        c = c.astype(np.int8)
    c = np.ascontiguousarray(c)
    return pa.Array.from_buffers(pa.from_numpy_dtype(c.dtype), len(c), [None, pa.py_buffer(c)])


def _column_info(cols: dict, units: dict | None) -> dict:
    return {
        n: {"dtype": c.dtype.str if c.dtype.kind != "U" else "str", "unit": (units or {}).get(n)}
        for n, c in cols.items()
    }


def _arrow_table(cols: dict):
    import pyarrow as pa

    return pa.table({n: _arrow_column(pa, c) for n, c in cols.items()})


#: Parquet compression: zstd at a low level is about as fast as snappy here, files about
#: half the size
_PARQUET_OPTIONS = {"compression": "zstd", "compression_level": 1}


def _write_parquet(path: Path, cols: dict, info: dict) -> None:
    import pyarrow.parquet as pq

    table = _arrow_table(cols).replace_schema_metadata({_KEY: json.dumps(info, allow_nan=True)})
    pq.write_table(table, path, **_PARQUET_OPTIONS)


def _csv_head(info: dict) -> str:
    """The metadata line and the header line of a CSV table."""
    header = ",".join(f"{n} [{u}]" if (u := d["unit"]) else n for n, d in info["columns"].items())
    return f"# {_KEY}: {json.dumps(info, allow_nan=True)}\n{header}\n"


def _csv_rows(f, cols: dict) -> None:
    """Write the rows of ``cols`` to the open text file ``f``."""
    names = list(cols)
    if not names or len(cols[names[0]]) == 0:
        return
    fmts = [
        "%s" if cols[n].dtype.kind in "USO" else "%d" if cols[n].dtype.kind in "iub" else "%.17g"
        for n in names
    ]
    rows = np.empty((len(cols[names[0]]), len(names)), dtype=object)
    for j, n in enumerate(names):
        rows[:, j] = cols[n]
    np.savetxt(f, rows, fmt=fmts, delimiter=",")


def _write_csv(path: Path, cols: dict, info: dict) -> None:
    with gzip.open(path, "wt", compresslevel=1, newline="\n") as f:
        f.write(_csv_head(info))
        _csv_rows(f, cols)


class TableWriter:
    """A table written in pieces, for data that does not fit in memory at once: rows are
    appended as they arrive and the metadata (known only at the end) is added by
    :meth:`close`; :func:`read_table` reads the result as if :func:`write_table` had
    written it whole.

        w = TableWriter("out/timeseries", units={"t": "s"})
        w.append(columns)            # as often as needed, same names and dtypes
        w.close(metadata={...})      # -> out/timeseries.parquet, renamed into place

    Until :meth:`close` the rows are in a temporary file (``NAME.partial.SUFFIX``), so a
    table that was cut off is never taken for a whole one; :meth:`abort` removes it.
    Parquet gets one row group per :data:`ROW_GROUP_ROWS` rows (the rows in between are
    held in memory); CSV is written as two gzip members, the metadata and header line
    first, the rows (streamed to a second temporary file) appended to it by copying.
    """

    #: rows gathered before a Parquet row group is written (a streamed run appends 10 000
    #: rows at a time: one row group each, ~5 MB of a time series' 60 columns in memory)
    ROW_GROUP_ROWS = 8192

    def __init__(self, stem, *, units: dict | None = None, fmt: str | None = None):
        self.fmt = fmt or default_format()
        self.path = table_path(stem, self.fmt)
        self.units = dict(units or {})
        suffix = SUFFIXES[self.fmt]
        stem_name = self.path.name[: -len(suffix)]
        # temporary names that a run directory sweeps away as stale (run_directory)
        self._tmp = self.path.with_name(stem_name + PARTIAL_SUFFIX + suffix)
        self._body = self.path.with_name(stem_name + PARTIAL_SUFFIX + ".rows" + suffix)
        self._columns: dict | None = None  # name -> {"dtype", "unit"}
        self._pending: list[dict] = []
        self._n_pending = 0
        self._writer: Any = None  # pyarrow.parquet.ParquetWriter while writing Parquet
        self._file: Any = None  # the gzip text stream while writing CSV
        self.n_rows = 0

    def append(self, columns: dict) -> None:
        """Add rows: ``columns`` name -> 1-D array, the same names and dtypes each time."""
        cols = {n: np.asarray(c) for n, c in columns.items()}
        lengths = {len(c) for c in cols.values()}
        if len(lengths) > 1:
            raise ValueError(f"columns of unequal length: {sorted(lengths)}")
        info = _column_info(cols, self.units)
        if self._columns is None:
            self._columns = info
        elif info != self._columns:
            raise ValueError(
                f"{self.path}: appended columns differ from the first ones (names or dtypes)"
            )
        n = lengths.pop() if lengths else 0
        self.n_rows += n
        if self.fmt == "csv":
            if self._file is None:
                self._file = gzip.open(self._body, "wt", compresslevel=1, newline="\n")
            _csv_rows(self._file, cols)
            return
        self._pending.append(cols)
        self._n_pending += n
        if self._n_pending >= self.ROW_GROUP_ROWS:
            self._flush()

    def _flush(self) -> None:
        if not self._pending:
            return
        import pyarrow.parquet as pq

        cols = {n: np.concatenate([p[n] for p in self._pending]) for n in self._columns or {}}
        table = _arrow_table(cols)
        if self._writer is None:
            self._writer = pq.ParquetWriter(self._tmp, table.schema, **_PARQUET_OPTIONS)
        self._writer.write_table(table)
        self._pending, self._n_pending = [], 0

    def close(self, metadata: dict | None = None) -> Path:
        """Finish the table with its ``metadata`` and rename it into place; the path."""
        if self._columns is None:
            raise ValueError(
                f"{self.path}: no rows were appended (the column names and "
                "dtypes come from the first append)"
            )
        info = {"columns": self._columns, "metadata": metadata or {}}
        try:
            if self.fmt == "parquet":
                self._flush()
                self._writer.add_key_value_metadata({_KEY: json.dumps(info, allow_nan=True)})
                self._writer.close()
                self._writer = None
            else:
                if self._file is not None:
                    self._file.close()
                    self._file = None
                with open(self._tmp, "wb") as out:
                    out.write(gzip.compress(_csv_head(info).encode(), compresslevel=1))
                    if self._body.exists():
                        with open(self._body, "rb") as body:
                            shutil.copyfileobj(body, out, 1 << 20)
                self._body.unlink(missing_ok=True)
            os.replace(self._tmp, self.path)
        except BaseException:
            self.abort()
            raise
        return self.path

    def abort(self) -> None:
        """Give the table up: close and remove the temporary files."""
        for f in (self._writer, self._file):
            try:
                if f is not None:
                    f.close()
            except Exception:  # noqa: BLE001 - removing it is all that is left to do
                pass
        self._writer = self._file = None
        for p in (self._tmp, self._body):
            try:
                p.unlink()
            except OSError:
                pass


def read_metadata(path) -> dict:
    """The metadata and column information of a table without reading its rows:
    ``{"columns": {name: {"dtype", "unit"}}, "metadata": {...}}``."""
    path = Path(path)
    fmt = _format_of(path)
    try:
        if fmt == "parquet":
            import pyarrow.parquet as pq

            # the file's key-value metadata: the schema's (write_table) or added at the
            # end (TableWriter)
            raw = (pq.ParquetFile(path).metadata.metadata or {}).get(_KEY.encode())
        else:
            with gzip.open(path, "rt") as f:
                first = f.readline()
            raw = first[len(f"# {_KEY}: ") :] if first.startswith(f"# {_KEY}: ") else None
    except ImportError:
        raise
    except Exception as exc:  # pyarrow / gzip errors of damaged or foreign files
        raise TableError(f"{path}: cannot read: {exc}") from None
    if raw is None:
        raise TableError(f"{path}: not a table written by scoutsim (no '{_KEY}' metadata)")
    return json.loads(raw)


def read_table(path, *, t_range: tuple[float, float] | None = None) -> tuple[dict, dict]:
    """(columns, metadata) of a table written by :func:`write_table` (or
    :class:`TableWriter`), with the dtypes it was written with.

    ``t_range`` = (t0, t1): only the rows with t0 <= column ``t`` <= t1 [s]. A Parquet
    table reads only the row groups that can hold them (their statistics), so a window of a
    run streamed to disk costs what the window holds; a CSV table is read whole, then cut.
    """
    path = Path(path)
    info = read_metadata(path)
    spec = info["columns"]
    if _format_of(path) == "parquet":
        import pyarrow.parquet as pq

        filters = (
            None
            if t_range is None
            else [("t", ">=", float(t_range[0])), ("t", "<=", float(t_range[1]))]
        )
        table = pq.read_table(path, filters=filters)
        cols = {n: table.column(n).to_numpy(zero_copy_only=False) for n in spec}
    else:
        cols = _read_csv(path, spec)
        if t_range is not None:
            keep = (cols["t"] >= t_range[0]) & (cols["t"] <= t_range[1])
            cols = {n: c[keep] for n, c in cols.items()}
    for n, d in spec.items():
        cols[n] = cols[n].astype(str) if d["dtype"] == "str" else cols[n].astype(d["dtype"])
    return cols, info["metadata"]


def _read_csv(path: Path, spec: dict) -> dict:
    names = list(spec)
    with gzip.open(path, "rt") as f:
        f.readline()
        f.readline()
        text = f.read()
    if not text.strip():
        return {n: np.zeros(0) for n in names}
    strings = [j for j, n in enumerate(names) if spec[n]["dtype"] == "str"]
    if strings:
        raw = np.array([line.split(",") for line in text.splitlines()], dtype=object)
        return {
            n: (raw[:, j].astype(str) if j in strings else raw[:, j].astype(float))
            for j, n in enumerate(names)
        }
    data = np.loadtxt(text.splitlines(), delimiter=",", ndmin=2)
    return {n: data[:, j] for j, n in enumerate(names)}
