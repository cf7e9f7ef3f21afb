"""A log table: CSV (header row of names, or none) or MATLAB .mat (one matrix variable, or
one vector variable per column), its columns addressed by name or 0-based index.

Cells are kept as read so that times convert to integer nanoseconds exactly (a CSV's decimal
text, not its nearest float); every other column is read as float64, an empty cell as NaN.
Messages name the file, the column and the file's line (CSV) or row (1-based, .mat).
"""
from __future__ import annotations

import csv
from decimal import ROUND_HALF_EVEN, Decimal, InvalidOperation
from pathlib import Path

import numpy as np

from .column_units import TIME_NS, LogError

ColumnRef = str | int
"""A column by its header name (or .mat variable name) or its 0-based index."""


def _number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


class Table:
    """The rows of one log file. `lines` (N,): where each row is in the file (CSV line
    numbers, 1-based, header included; .mat row numbers, 1-based)."""

    def __init__(self, source: str, names: list[str], columns: list, lines: np.ndarray,
                 by_variable: dict[str, np.ndarray] | None = None, line_word: str = 'row') -> None:
        self.source = source
        self.names = names
        self._columns = columns            # per column: list of str (CSV) or float array (.mat)
        self._by_variable = by_variable or {}
        self.lines = lines
        self.line_word = line_word

    def __len__(self) -> int:
        return len(self.lines)

    def _index(self, ref: ColumnRef, what: str) -> int | str:
        if isinstance(ref, bool) or not isinstance(ref, (int, str)):
            raise LogError(f'{self.source}: {what}: a column is a name or a 0-based index, got {ref!r}')
        if isinstance(ref, int):
            if not 0 <= ref < len(self._columns):
                raise LogError(f'{self.source}: {what}: column index {ref} out of range '
                               f'(the file has {len(self._columns)} columns, 0-based)')
            return ref
        if ref in self._by_variable:
            return ref
        if ref in self.names:
            return self.names.index(ref)
        have = ', '.join(self.names or list(self._by_variable)) or 'none'
        raise LogError(f'{self.source}: {what}: no column named {ref!r} (columns: {have})')

    def label(self, ref: ColumnRef) -> str:
        if isinstance(ref, int) and ref < len(self.names) and self.names[ref]:
            return f'column {ref} ({self.names[ref]!r})'
        return f'column {ref!r}' if isinstance(ref, str) else f'column {ref}'

    def _raw(self, ref: ColumnRef, what: str):
        k = self._index(ref, what)
        if isinstance(k, str):
            col = self._by_variable[k]
            if len(col) != len(self.lines):
                raise LogError(f'{self.source}: variable {k!r} has {len(col)} rows, the table {len(self.lines)}')
            return col
        return self._columns[k]

    def floats(self, ref: ColumnRef, what: str) -> np.ndarray:
        """Column `ref` as float64 (N,); an empty cell is NaN; text that is not a number is an
        error naming its line."""
        col = self._raw(ref, what)
        if not isinstance(col, list):
            return np.asarray(col, dtype=float)
        out = np.empty(len(col))
        for i, text in enumerate(col):
            t = text.strip()
            if not t:
                out[i] = np.nan
                continue
            try:
                out[i] = float(t)
            except ValueError:
                raise LogError(f'{self.source}: {what}: {self.label(ref)} {self.line_word} {self.lines[i]}: '
                               f'{text!r} is not a number') from None
        return out

    def times_ns(self, ref: ColumnRef, unit: str, what: str, keep: np.ndarray) -> np.ndarray:
        """Column `ref` (time in `unit`) as integer nanoseconds (N,) for the rows `keep`
        (bool mask; the others hold 0); a CSV's decimal text converts exactly."""
        if unit not in TIME_NS:
            raise LogError(f'{self.source}: {what}: time unit {unit!r} is not one of {", ".join(TIME_NS)}')
        scale = TIME_NS[unit]
        col = self._raw(ref, what)
        out = np.zeros(len(self.lines), dtype=np.int64)
        if not isinstance(col, list):
            v = np.asarray(col, dtype=float)
            out[keep] = np.round(v[keep] * scale).astype(np.int64)
            return out
        d_scale = Decimal(scale)
        for i in np.flatnonzero(keep):
            try:
                out[i] = int((Decimal(col[i].strip()) * d_scale).to_integral_value(ROUND_HALF_EVEN))
            except InvalidOperation:
                raise LogError(f'{self.source}: {what}: {self.label(ref)} {self.line_word} {self.lines[i]}: '
                               f'{col[i]!r} is not a number') from None
        return out


def read_csv(path: Path, header: bool = True, delimiter: str | None = None) -> Table:
    """A CSV (or whitespace-separated) file; lines starting with '#' are comments. With
    `header`, the first line is the column names (an error if it holds only numbers)."""
    text = Path(path).read_text(encoding='utf-8-sig')     # a spreadsheet's byte-order mark dropped
    numbered = [(i + 1, ln) for i, ln in enumerate(text.splitlines())
                if ln.strip() and not ln.lstrip().startswith('#')]
    if not numbered:
        raise LogError(f'{path}: empty file')
    first = numbered[0][1]
    if delimiter is None:
        delimiter = next((d for d in (',', ';', '\t') if d in first), ' ')
    if delimiter == ' ':
        rows = [(n, ln.split()) for n, ln in numbered]
    else:
        rows = [(n, cells) for (n, _), cells in zip(numbered, csv.reader([ln for _, ln in numbered],
                                                                         delimiter=delimiter))]
    names: list[str] = []
    if header:
        names = [c.strip() for c in rows[0][1]]
        if all(_number(c) for c in names):
            raise LogError(f'{path}: line {rows[0][0]}: a header row of column names is required '
                           f'(found numbers: {rows[0][1][:4]}...)')
        rows = rows[1:]
    if not rows:
        raise LogError(f'{path}: no data rows')
    width = len(names) if header else len(rows[0][1])
    for n, cells in rows:
        if len(cells) != width:
            raise LogError(f'{path}: line {n}: {len(cells)} fields, expected {width}')
    columns = [[cells[k] for _, cells in rows] for k in range(width)]
    return Table(str(path), names, columns, np.array([n for n, _ in rows], dtype=np.int64), line_word='line')


def read_mat(path: Path, variable: str | None = None, names: list[str] | None = None) -> Table:
    """A MATLAB .mat file (v4-v7.2, scipy.io): `variable` a matrix (N, C) whose columns are
    addressed by index or by `names`; without it, each column is a vector variable by name."""
    from scipy.io import loadmat
    try:
        data = loadmat(str(path))
    except (NotImplementedError, ValueError) as e:
        raise LogError(f'{path}: cannot read as a MATLAB .mat file ({e}; a v7.3 file must be '
                       f'saved with -v7 or exported to CSV)') from None
    vars_ = {k: v for k, v in data.items() if not k.startswith('__')}
    if variable is not None:
        if variable not in vars_:
            raise LogError(f'{path}: no variable {variable!r} (variables: {", ".join(vars_)})')
        m = np.atleast_2d(np.asarray(vars_[variable], dtype=float))
        if names and len(names) != m.shape[1]:
            raise LogError(f'{path}: {len(names)} names for the {m.shape[1]} columns of {variable!r}')
        return Table(str(path), list(names or []), [m[:, k] for k in range(m.shape[1])],
                     np.arange(1, m.shape[0] + 1))
    vectors = {}
    for k, v in vars_.items():
        a = np.asarray(v)
        if a.dtype.kind in 'fiu' and a.ndim <= 2 and min(a.shape or (1,)) == 1 and a.size > 1:
            vectors[k] = a.astype(float).ravel()
    if not vectors:
        raise LogError(f'{path}: no vector variables (give `variable:` for a matrix)')
    n = max(len(v) for v in vectors.values())
    return Table(str(path), [], [], np.arange(1, n + 1), by_variable=vectors)


def read_table(path: Path, *, header: bool = True, delimiter: str | None = None,
               variable: str | None = None, names: list[str] | None = None) -> Table:
    """A .mat file by its extension, else a CSV."""
    path = Path(path)
    if not path.exists():
        raise LogError(f'{path}: no such file')
    if path.suffix.lower() == '.mat':
        return read_mat(path, variable, names)
    return read_csv(path, header, delimiter)
