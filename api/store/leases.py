"""Leases: a run is driven by exactly one coordinator at a time.

A coordinator owns a run while `runs.lease_owner` is its id and `runs.lease_expires` (unix time)
lies ahead; it renews the lease with a heartbeat. A coordinator that dies stops renewing, and once
the lease expires any other coordinator (or the same one restarted) may take the run over. Every
write a driver makes is fenced by `owns()` in the same transaction, so a coordinator that lost its
lease (paused, partitioned) can never write over its successor.
"""

from __future__ import annotations

import time

from sqlalchemy import Connection, bindparam, case, or_, select, update

from softevo.api.db import Database
from softevo.api.models import RunRow
from softevo.api.store.runs import now
from softevo.api.store.statements import DriverStatement
from softevo.core.status import RunStatus


def _orphaned(at: float):  # type: ignore[no-untyped-def]
    return or_(
        RunRow.status == RunStatus.QUEUED,
        (RunRow.status == RunStatus.RUNNING)
        & (or_(RunRow.lease_expires.is_(None), RunRow.lease_expires < at)),
    )


# the same predicate as `acquire`'s, its time a bound parameter: compiled once, not per tick
_CANDIDATES = (
    select(RunRow.id)
    .where(_orphaned(bindparam("b_at")))
    .order_by(RunRow.id)
    .limit(bindparam("b_limit"))
)


def candidates(db: Database, limit: int, at: float | None = None) -> list[int]:
    """Runs waiting for a coordinator: queued ones, and running ones whose lease expired. (One
    precompiled Core statement: every coordinator runs it twice a second.)"""
    with db.engine.connect() as connection:
        when = time.time() if at is None else at
        return list(connection.execute(_CANDIDATES, {"b_at": when, "b_limit": limit}).scalars())


def acquire(db: Database, run_id: int, owner: str, seconds: float, at: float | None = None) -> bool:
    """Take the run if it is queued or its lease has expired (by `at`, unix time; default now)."""
    at = time.time() if at is None else at
    with db.write_session() as session:
        result = session.execute(
            update(RunRow)
            .where(RunRow.id == run_id, _orphaned(at))
            .values(
                status=RunStatus.RUNNING.value,
                lease_owner=owner,
                lease_expires=at + seconds,
                started_at=case((RunRow.started_at.is_(None), now()), else_=RunRow.started_at),
                takeovers=case(
                    (RunRow.status == RunStatus.RUNNING, RunRow.takeovers + 1),
                    else_=RunRow.takeovers,
                ),
            )
        )
        return result.rowcount == 1


_RENEW = DriverStatement(
    update(RunRow.__table__)
    .where(
        RunRow.__table__.c.id == bindparam("b_run"),
        RunRow.__table__.c.lease_owner == bindparam("b_owner"),
        RunRow.__table__.c.status == RunStatus.RUNNING.value,
    )
    .values(lease_expires=bindparam("b_expires"))
)


def owns(connection: Connection, run_id: int, owner: str, seconds: float) -> bool:
    """Renew the lease inside `connection`'s transaction; False if this owner lost the run. (One
    precompiled Core statement: it runs before every write a driver makes.)"""
    params = {"b_run": run_id, "b_owner": owner, "b_expires": time.time() + seconds}
    return _RENEW.execute(connection, [params]) == 1


def renew(db: Database, run_id: int, owner: str, seconds: float) -> bool:
    with db.write_connection() as connection:
        return owns(connection, run_id, owner, seconds)


def release_all(db: Database, owner: str) -> None:
    """Let every run of `owner` be taken over at once (a clean shutdown)."""
    with db.write_session() as session:
        session.execute(
            update(RunRow)
            .where(RunRow.lease_owner == owner, RunRow.status == RunStatus.RUNNING)
            .values(lease_owner=None, lease_expires=None)
        )
