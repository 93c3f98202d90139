"""The sweep table: one row per member (options, metrics, status, error, wall time).

Written as ``sweep.csv`` and ``sweep.parquet``, each replaced atomically (written beside,
then renamed), so that a reader, or a sweep killed at any moment, never sees half a table.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from quadcosim.infra.files import atomic_path

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


#: Rows converted to Arrow at a time when the Parquet file is written.
BATCH_ROWS = 4096
_EMPTY, _OK, _FAILED, _DIVERGED = 0, 1, 2, 3  # a member's state in :class:`Rows`
#: A member's outcome, in its ``status`` column: ``ok`` (its metrics are a result), ``diverged``
#: (it ran to the end, but its flight crossed the scenario's bounds: its numbers describe a crash,
#: never a result), ``failed`` (it raised, gave a NaN, or its worker died); ``interrupted`` is the
#: outcome of a member a signal stopped before it finished (counted, never written as a row).
OUTCOMES = ("ok", "diverged", "failed", "interrupted")


class Rows:
    """The rows of a sweep's table, kept on disk as members finish, not in memory.

    Each row goes, as one JSON line, to an unnamed temporary file in the sweep folder (gone
    with the process, however it ends); memory keeps 17 bytes per member of the plan (where
    its row is, and whether it finished well) and, per column, where it first appears and the
    kinds of value it holds. :meth:`write` streams the table in member order from that file, so
    a sweep's client stays flat however many members it has.

    Parameters
    ----------
    size : int
        Members of the plan (indices 0 to ``size - 1``).
    folder : pathlib.Path
        Where the temporary file lives (the sweep folder).
    """

    def __init__(self, size: int, folder: Path):
        import tempfile
        from array import array

        self._file = tempfile.TemporaryFile(dir=folder)
        self._offset = array("q", bytes(8 * size))  # where each member's line starts, bytes
        self._length = array("q", bytes(8 * size))  # its length, bytes
        self._state = bytearray(size)  # _EMPTY, _OK, _FAILED or _DIVERGED
        self._columns: dict[str, tuple[int, int]] = {}  # name -> (first member holding it, position in its row)
        self._kinds: dict[str, dict] = {}  # name -> value type -> a value of it (ints: the least and largest)
        self._replaced = False  # a row was replaced since the columns were counted
        self.units: dict[str, str] = {}  # option name -> unit (the metrics' come from their names)
        self.ok = 0
        self.failures: dict[int, tuple[str, str | None]] = {}  # failed member -> (label, error)
        self.divergences: dict[int, tuple[str, str | None]] = {}  # diverged member -> (label, what crossed)

    def __len__(self) -> int:
        return self.ok + len(self.failures) + len(self.divergences)

    def finished(self, index: int) -> bool:
        """Whether member ``index`` has a known outcome that running it again would not change:
        it finished well, or it diverged (members are deterministic)."""
        return self._state[index] in (_OK, _DIVERGED)

    def add(self, index: int, row: dict) -> None:
        """Keep member ``index``'s row (:func:`row`), in the place of one it had."""
        line = json.dumps(row, default=_plain_value).encode() + b"\n"
        self._file.seek(0, 2)
        self._offset[index], self._length[index] = self._file.tell(), len(line)
        self._file.write(line)
        if self._state[index] == _OK:
            self.ok -= 1
        self._replaced |= self._state[index] != _EMPTY  # what the row it replaces held may be gone
        self.failures.pop(index, None)
        self.divergences.pop(index, None)
        if row["status"] == "ok":
            self._state[index] = _OK
            self.ok += 1
        elif row["status"] == "diverged":
            self._state[index] = _DIVERGED
            self.divergences[index] = (row.get("label"), row.get("error"))
        else:
            self._state[index] = _FAILED
            self.failures[index] = (row.get("label"), row.get("error"))
        self._note(index, row)

    def _note(self, index: int, row: dict) -> None:
        """Count the columns of member ``index``'s row: where each first appears, its kinds of value."""
        for position, (name, value) in enumerate(row.items()):
            first = self._columns.get(name)
            if first is None or index < first[0]:
                self._columns[name] = (index, position)
            kinds = self._kinds.setdefault(name, {})
            kind = type(value)
            if kind is int:
                least, largest = kinds.get(int, (value, value))
                kinds[int] = (min(least, value), max(largest, value))
            elif kind not in kinds:
                kinds[kind] = value

    def names(self) -> list[str]:
        """Every column, in the order of :func:`columns_of` over the rows in member order."""
        if self._replaced:  # counted again from the rows kept, one at a time
            self._file.flush()
            self._columns, self._kinds, self._replaced = {}, {}, False
            for index, state in enumerate(self._state):
                if state != _EMPTY:
                    self._note(index, self._read(index))
        return sorted(self._columns, key=self._columns.__getitem__)

    def _read(self, index: int) -> dict:
        self._file.seek(self._offset[index])
        return json.loads(self._file.read(self._length[index]))

    def __iter__(self):
        """The rows, in member order, read back one at a time."""
        self._file.flush()
        for index, state in enumerate(self._state):
            if state != _EMPTY:
                yield self._read(index)

    def _arrow_type(self, name: str):
        """The Arrow type ``pyarrow.array`` infers for the whole column ``name``, found from one value
        of each kind it holds (the least and the largest integer), or None where values of kinds
        Arrow cannot hold in one column make it a column of text (JSON)."""
        samples = [None]
        for kind, value in self._kinds[name].items():
            samples += list(value) if kind is int else [value]
        try:
            return pa.array(samples).type
        except (pa.ArrowInvalid, pa.ArrowTypeError, TypeError, OverflowError):
            return None

    def write(self, out: Path) -> None:
        """Write ``sweep.csv`` and ``sweep.parquet`` in ``out``, each atomically, streamed from
        the rows on disk."""
        names = self.names()

        def csv_file(path):
            with open(path, "w", newline="") as handle:
                writer = csv.writer(handle)
                writer.writerow(names)
                for r in self:
                    writer.writerow(["" if r.get(n) is None else repr(r[n]) if isinstance(r[n], float) else r[n]
                                     for n in names])

        def parquet_file(path):
            types = {n: self._arrow_type(n) for n in names}
            from quadcosim.studies.sweep.units import of_columns

            unit = of_columns(names, self.units)
            schema = pa.schema([pa.field(n, pa.string() if t is None else t,
                                         metadata={"unit": unit[n]} if n in unit else None)
                                for n, t in types.items()])
            with pq.ParquetWriter(path, schema) as writer:
                batch = []
                for r in self:
                    batch.append(r)
                    if len(batch) == BATCH_ROWS:
                        writer.write_table(_arrow_batch(batch, types, schema))
                        batch = []
                if batch:
                    writer.write_table(_arrow_batch(batch, types, schema))

        _replace(out / "sweep.csv", csv_file)
        _replace(out / "sweep.parquet", parquet_file)

    def close(self) -> None:
        """Remove the rows' temporary file."""
        self._file.close()


def _plain_value(value):
    """A NumPy scalar as the Python number it holds; anything else as its text."""
    return value.item() if hasattr(value, "item") else str(value)


def _text(value):
    return None if value is None else json.dumps(value, default=str) if not isinstance(value, str) else value


def _arrow_batch(rows: list[dict], types: dict, schema) -> pa.Table:
    """Rows as an Arrow table of ``schema``: each column of its type, or as text (``types[n]`` None)."""
    columns = {}
    for name, kind in types.items():
        values = [r.get(name) for r in rows]
        columns[name] = pa.array([_text(v) for v in values], type=pa.string()) if kind is None else \
            pa.array(values, type=kind)
    return pa.table(columns, schema=schema)


def _replace(path: Path, write):
    with atomic_path(path) as temporary:
        write(temporary)


def write(rows: list[dict], out: Path) -> None:
    """Write the ``rows`` as ``sweep.csv`` and ``sweep.parquet`` in ``out``, each atomically."""
    kept = Rows(max((r["member"] for r in rows), default=-1) + 1, out)
    try:
        for r in rows:
            kept.add(r["member"], r)
        kept.write(out)
    finally:
        kept.close()


def units(path) -> dict[str, str]:
    """The unit of each column of a sweep table that has one, from ``path``: a sweep folder or its
    ``sweep.parquet`` (each field's metadata ``unit``)."""
    path = Path(path)
    schema = pq.read_schema(path / "sweep.parquet" if path.is_dir() else path)
    return {field.name: field.metadata[b"unit"].decode() for field in schema
            if field.metadata and b"unit" in field.metadata}


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
