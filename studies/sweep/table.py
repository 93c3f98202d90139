"""The sweep table: one row per member (options, metrics, status, error, wall time).

Written as ``sweep.csv`` and ``sweep.parquet``, each replaced atomically (written beside,
then renamed), so that a reader, or a sweep killed at any moment, never sees half a table.
"""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from orchestrator.files import atomic_path

#: Columns that come first, in this order; the options and then the metrics follow.
LEADING = ("member", "label", "status", "error", "attempts", "wall_s", "cpu_s", "stepping_cpu_s", "worker")
#: Columns that depend on the run (timing, placement), not on the member's options.
VOLATILE = ("wall_s", "cpu_s", "stepping_cpu_s", "worker", "attempts", "real_time_factor")
#: Lists of at most this many numbers are spread over columns ``name[0]``, ``name[1]``...
SPREAD = 8


def flatten(metrics: dict, prefix: str = "") -> dict:
    """Scalar columns from a metrics dict: nested dicts as ``a.b``, short lists as ``a[i]``,
    anything else as JSON text; every name starts with ``prefix``."""
    flat = {}
    for key, value in metrics.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat |= flatten(value, f"{name}.")
        elif isinstance(value, list | tuple) and 0 < len(value) <= SPREAD and all(
                isinstance(v, int | float | bool) or v is None for v in value):
            flat |= {f"{name}[{i}]": v for i, v in enumerate(value)}
        elif value is None or isinstance(value, str | bool | int | float):
            flat[name] = value
        else:
            flat[name] = json.dumps(value, default=float)
    return flat


def row(record: dict, varied_first=()) -> dict:
    """The table row of one member ``record`` (as kept in its ``metrics.json``), the options named
    in ``varied_first`` first."""
    options = record["options"]
    metrics = flatten(record.get("metrics") or {})
    out = {key: record.get(key) for key in LEADING}
    out |= {k: options[k] for k in varied_first} | options
    for key, value in metrics.items():
        out[f"metric.{key}" if key in out else key] = value
    return out


def columns_of(rows: list[dict]) -> list[str]:
    """Every column of ``rows``, in the order they first appear."""
    names: dict[str, None] = {}
    for r in rows:
        names.update(dict.fromkeys(r))
    return list(names)


def _arrow_column(values: list) -> pa.Array:
    try:
        return pa.array(values)
    except (pa.ArrowInvalid, pa.ArrowTypeError, TypeError, OverflowError):
        return pa.array([None if v is None else json.dumps(v, default=str) if not isinstance(v, str) else v
                         for v in values])


def _replace(path: Path, write):
    with atomic_path(path) as temporary:
        write(temporary)


def write(rows: list[dict], out: Path) -> None:
    """Write the ``rows`` as ``sweep.csv`` and ``sweep.parquet`` in ``out``, each atomically."""
    rows = sorted(rows, key=lambda r: r["member"])
    names = columns_of(rows)

    def csv_file(path):
        buffer = io.StringIO()
        writer = csv.writer(buffer)
        writer.writerow(names)
        for r in rows:
            writer.writerow(["" if r.get(n) is None else repr(r[n]) if isinstance(r[n], float) else r[n]
                             for n in names])
        path.write_text(buffer.getvalue())

    def parquet_file(path):
        table = pa.table({n: _arrow_column([r.get(n) for r in rows]) for n in names})
        pq.write_table(table, path)

    _replace(out / "sweep.csv", csv_file)
    _replace(out / "sweep.parquet", parquet_file)


def read(path) -> dict[str, list]:
    """A sweep table as columns (name -> list), from ``path``: a sweep folder, a ``.parquet`` or a
    ``.csv``."""
    path = Path(path)
    if path.is_dir():
        path = path / "sweep.parquet"
    if path.suffix == ".parquet":
        return pq.read_table(path).to_pydict()
    with open(path, newline="") as handle:
        records = list(csv.DictReader(handle))
    columns = {name: [r[name] for r in records] for name in (records[0] if records else [])}
    return {name: [_number_or_text(v) for v in values] for name, values in columns.items()}


def _number_or_text(text: str):
    if text == "":
        return None
    if text in ("True", "False"):
        return text == "True"
    try:
        value = float(text)
    except ValueError:
        return text
    return int(value) if value.is_integer() and "." not in text and "e" not in text.lower() else value


def comparable(columns: dict[str, list]) -> dict[str, list]:
    """The table without the columns that depend on timing or placement (:data:`VOLATILE`)."""
    return {k: v for k, v in columns.items() if k not in VOLATILE}


def same(a: dict[str, list], b: dict[str, list]) -> bool:
    """Whether two tables hold the same values, volatile columns aside. NaN equals NaN, and an
    empty text equals a missing value (CSV writes both as an empty field)."""
    a, b = comparable(a), comparable(b)
    if list(a) != list(b):
        return False
    for name in a:
        if len(a[name]) != len(b[name]):
            return False
        for x, y in zip(a[name], b[name], strict=True):
            both_nan = isinstance(x, float) and isinstance(y, float) and math.isnan(x) and math.isnan(y)
            if x != y and not both_nan and {x, y} != {"", None}:
                return False
    return True
