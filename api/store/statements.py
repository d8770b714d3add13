"""Core statements compiled once per dialect and run straight through the driver (`executemany`
for many rows): the writes a driver makes every generation skip SQLAlchemy's per-statement and
per-row parameter machinery, which cost more than the database's own work. Values are converted
by the same bind processors SQLAlchemy would apply (JSON encoded, datetimes in SQLite's text
form), so the rows stored are the same.

On PostgreSQL a statement may also have a form for many rows: one statement that reads its rows
from one JSON text (`json_to_recordset`). psycopg's `executemany` sends and books every row on
its own, and that Python work cost the coordinator more CPU than the writes themselves."""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from sqlalchemy import JSON, Connection
from sqlalchemy.engine import Dialect
from sqlalchemy.sql.dml import UpdateBase

from softevo.api.db import encode_json

_NOTHING = object()  # no row's value


@dataclass(frozen=True)
class _Compiled:
    sql: str
    names: tuple[str, ...]  # the bound parameters, in the driver's order
    positional: bool  # qmark (SQLite) rather than named (psycopg)
    fixed: dict[str, Any]  # the statement's own literal values
    processors: tuple[tuple[int, Callable[[Any], Any]], ...]  # (position, to the driver's form)
    json_names: frozenset[str]  # the parameters of JSON columns

    def params(
        self, row: Mapping[str, Any], last: list[list[Any]]
    ) -> tuple[Any, ...] | dict[str, Any]:
        """The row in the driver's form; `last` (per processor: the last [object, its form])
        lets consecutive rows that share an object (a generation's timestamp) convert it once."""
        values = [row[name] if name in row else self.fixed[name] for name in self.names]
        for (position, process), seen in zip(self.processors, last, strict=True):
            value = values[position]
            if seen[0] is not value:
                seen[0], seen[1] = value, process(value)
            values[position] = seen[1]
        return tuple(values) if self.positional else dict(zip(self.names, values, strict=True))

    def recordset(
        self, rows: Sequence[Mapping[str, Any]], scalars: tuple[str, ...]
    ) -> dict[str, Any]:
        """The rows as `postgres_rows` takes them: `b_rows`, one JSON text of every row's
        values but the `scalars` (JSON columns' values as their text, timestamps in ISO form),
        and each scalar's one value."""
        shared = {name: rows[0][name] for name in scalars}
        if any(row[name] != value for row in rows for name, value in shared.items()):
            raise ValueError(f"rows differ in one of {scalars}, which they must share")
        plain = [
            {
                name: encode_json(row[name]) if name in self.json_names else row[name]
                for name in self.names
                if name in row and name not in shared
            }
            for row in rows
        ]
        return {**shared, "b_rows": json.dumps(plain, allow_nan=False, default=_iso)}


def _iso(value: Any) -> str:
    if isinstance(value, datetime):
        return value.isoformat()
    raise TypeError(f"{type(value).__name__} has no JSON form")


class DriverStatement:
    """An INSERT or UPDATE with bound parameters, run for rows of plain values (bound parameter
    name -> value, as `connection.execute` would take them).

    `postgres_rows`: the same write for PostgreSQL, used for two rows or more; it reads the rows
    from `%(b_rows)s` (`json_to_recordset`, columns named as the parameters) and the `scalars`,
    which every row shares, from their own parameters. Rows must not repeat a key the
    statement matches on (an UPDATE's row would meet itself twice)."""

    def __init__(
        self, statement: UpdateBase, postgres_rows: str | None = None, scalars: tuple[str, ...] = ()
    ) -> None:
        self.statement = statement
        self.postgres_rows = postgres_rows
        self.scalars = scalars
        self._by_dialect: dict[str, _Compiled] = {}

    def execute(self, connection: Connection, rows: Sequence[Mapping[str, Any]]) -> int:
        """Run the statement once per row, in one driver call; the rows it changed."""
        if not rows:
            return 0
        compiled = self._by_dialect.get(connection.dialect.name) or self._compile(
            connection.dialect
        )
        if self.postgres_rows and len(rows) > 1 and connection.dialect.name == "postgresql":
            params = compiled.recordset(rows, self.scalars)
            return connection.exec_driver_sql(self.postgres_rows, params).rowcount
        last: list[list[Any]] = [[_NOTHING, None] for _ in compiled.processors]
        params = [compiled.params(row, last) for row in rows]
        result = connection.exec_driver_sql(compiled.sql, params if len(params) > 1 else params[0])
        return result.rowcount

    def _compile(self, dialect: Dialect) -> _Compiled:
        compiled = self.statement.compile(dialect=dialect)
        positional = compiled.positiontup is not None
        if positional:
            names = tuple(compiled.positiontup or ())
        else:
            names = tuple(name for name in compiled.binds if f"%({name})s" in compiled.string)
        binds = compiled.binds
        processors = tuple(
            (position, process)
            for position, name in enumerate(names)
            if (process := binds[name].type.dialect_impl(dialect).bind_processor(dialect))
        )
        fixed = {name: binds[name].value for name in names if not binds[name].required}
        json_names = frozenset(name for name in names if isinstance(binds[name].type, JSON))
        found = _Compiled(compiled.string, names, positional, fixed, processors, json_names)
        self._by_dialect[dialect.name] = found
        return found
