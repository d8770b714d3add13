"""Core statements compiled once per dialect and run straight through the driver (`executemany`
for many rows): the writes a driver makes every generation skip SQLAlchemy's per-statement and
per-row parameter machinery, which cost more than the database's own work. Values are converted
by the same bind processors SQLAlchemy would apply (JSON encoded, datetimes in SQLite's text
form), so the rows stored are the same."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from sqlalchemy import Connection
from sqlalchemy.engine import Dialect
from sqlalchemy.sql.dml import UpdateBase

_NOTHING = object()  # no row's value


@dataclass(frozen=True)
class _Compiled:
    sql: str
    names: tuple[str, ...]  # the bound parameters, in the driver's order
    positional: bool  # qmark (SQLite) rather than named (psycopg)
    fixed: dict[str, Any]  # the statement's own literal values
    processors: tuple[tuple[int, Callable[[Any], Any]], ...]  # (position, to the driver's form)

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


class DriverStatement:
    """An INSERT or UPDATE with bound parameters, run for rows of plain values (bound parameter
    name -> value, as `connection.execute` would take them)."""

    def __init__(self, statement: UpdateBase) -> None:
        self.statement = statement
        self._by_dialect: dict[str, _Compiled] = {}

    def execute(self, connection: Connection, rows: Sequence[Mapping[str, Any]]) -> int:
        """Run the statement once per row, in one driver call; the rows it changed."""
        if not rows:
            return 0
        compiled = self._by_dialect.get(connection.dialect.name) or self._compile(
            connection.dialect
        )
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
        found = _Compiled(compiled.string, names, positional, fixed, processors)
        self._by_dialect[dialect.name] = found
        return found
