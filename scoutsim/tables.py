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
from pathlib import Path

import numpy as np

from .run_directory import atomic_write

__all__ = ["FORMATS", "SUFFIXES", "default_format", "write_table", "read_table",
           "read_metadata", "table_path", "TableError"]

#: table formats and the suffix of their files
SUFFIXES = {"parquet": ".parquet", "csv": ".csv.gz"}
FORMATS = tuple(SUFFIXES)
_KEY = "scoutsim"


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


def write_table(stem, columns: dict, *, units: dict | None = None,
                metadata: dict | None = None, fmt: str | None = None) -> Path:
    """Write ``columns`` (name -> 1-D array, equal lengths) to ``stem`` + the format's
    suffix; ``units`` (name -> unit string) and ``metadata`` (JSON-safe, NaN allowed) are
    stored with it. The file is written whole or not at all
    (:func:`scoutsim.run_directory.atomic_write`). Returns the path."""
    fmt = fmt or default_format()
    path = table_path(stem, fmt)
    cols = {n: np.asarray(c) for n, c in columns.items()}
    lengths = {len(c) for c in cols.values()}
    if len(lengths) > 1:
        raise ValueError(f"columns of unequal length: {sorted(lengths)}")
    info = {"columns": {n: {"dtype": c.dtype.str if c.dtype.kind != "U" else "str",
                            "unit": (units or {}).get(n)} for n, c in cols.items()},
            "metadata": metadata or {}}
    writer = _write_parquet if fmt == "parquet" else _write_csv
    return atomic_write(path, lambda tmp: writer(tmp, cols, info))


def _arrow_column(pa, c: np.ndarray):
    """``c`` as an Arrow array built on its buffers (``pa.array`` would import pandas, if
    installed, on its first call: 0.3 s of a short run's command)."""
    if c.dtype.kind == "U":
        data = [x.encode() for x in c.tolist()]
        offsets = np.zeros(len(data) + 1, dtype=np.int32)
        offsets[1:] = np.cumsum([len(d) for d in data])
        return pa.Array.from_buffers(pa.string(), len(data),
                                     [None, pa.py_buffer(offsets), pa.py_buffer(b"".join(data))])
    if c.dtype.kind == "b":
        c = c.astype(np.int8)
    c = np.ascontiguousarray(c)
    return pa.Array.from_buffers(pa.from_numpy_dtype(c.dtype), len(c), [None, pa.py_buffer(c)])


def _write_parquet(path: Path, cols: dict, info: dict) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq
    table = pa.table({n: _arrow_column(pa, c) for n, c in cols.items()})
    table = table.replace_schema_metadata({_KEY: json.dumps(info, allow_nan=True)})
    # zstd at a low level: about as fast as snappy here, files about half the size
    pq.write_table(table, path, compression="zstd", compression_level=1)


def _write_csv(path: Path, cols: dict, info: dict) -> None:
    names = list(cols)
    header = ",".join(f"{n} [{u}]" if (u := info["columns"][n]["unit"]) else n
                      for n in names)
    with gzip.open(path, "wt", compresslevel=1, newline="\n") as f:
        f.write(f"# {_KEY}: {json.dumps(info, allow_nan=True)}\n{header}\n")
        if not names or len(cols[names[0]]) == 0:
            return
        fmts = ["%s" if cols[n].dtype.kind in "USO" else
                "%d" if cols[n].dtype.kind in "iub" else "%.17g" for n in names]
        rows = np.empty((len(cols[names[0]]), len(names)), dtype=object)
        for j, n in enumerate(names):
            rows[:, j] = cols[n]
        np.savetxt(f, rows, fmt=fmts, delimiter=",")


def read_metadata(path) -> dict:
    """The metadata and column information of a table without reading its rows:
    ``{"columns": {name: {"dtype", "unit"}}, "metadata": {...}}``."""
    path = Path(path)
    fmt = _format_of(path)
    try:
        if fmt == "parquet":
            import pyarrow.parquet as pq
            raw = (pq.read_schema(path).metadata or {}).get(_KEY.encode())
        else:
            with gzip.open(path, "rt") as f:
                first = f.readline()
            raw = first[len(f"# {_KEY}: "):] if first.startswith(f"# {_KEY}: ") else None
    except ImportError:
        raise
    except Exception as exc:   # pyarrow / gzip errors of damaged or foreign files
        raise TableError(f"{path}: cannot read: {exc}") from None
    if raw is None:
        raise TableError(f"{path}: not a table written by scoutsim (no '{_KEY}' metadata)")
    return json.loads(raw)


def read_table(path) -> tuple[dict, dict]:
    """(columns, metadata) of a table written by :func:`write_table`, with the dtypes it
    was written with."""
    path = Path(path)
    info = read_metadata(path)
    spec = info["columns"]
    if _format_of(path) == "parquet":
        import pyarrow.parquet as pq
        table = pq.read_table(path)
        cols = {n: table.column(n).to_numpy(zero_copy_only=False) for n in spec}
    else:
        cols = _read_csv(path, spec)
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
        return {n: (raw[:, j].astype(str) if j in strings else raw[:, j].astype(float))
                for j, n in enumerate(names)}
    data = np.loadtxt(text.splitlines(), delimiter=",", ndmin=2)
    return {n: data[:, j] for j, n in enumerate(names)}
