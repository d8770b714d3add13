"""The reads of a run's Pareto front: every evaluated individual's measures, streamed, and the
genomes of the few on the front."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from sqlalchemy import select, tuple_

from softevo.api.db import Database
from softevo.api.models import IndividualRow
from softevo.core.status import IndividualStatus


def evaluated(db: Database, run_id: int, chunk: int = 4096) -> Iterator[dict[str, Any]]:
    """Every evaluated individual of the run (simulated or from the cache), in (generation,
    index) order, fetched `chunk` rows at a time and never with its genome; a genome met again
    keeps its `genome_hash`, by which `front_rows` counts it once."""
    with db.read_session() as session:
        result = session.execute(
            select(
                IndividualRow.generation,
                IndividualRow.index,
                IndividualRow.fitness,
                IndividualRow.operator,
                IndividualRow.measures,
                IndividualRow.genome_hash,
            )
            .where(
                IndividualRow.run_id == run_id,
                IndividualRow.status.in_(
                    [IndividualStatus.EVALUATED.value, IndividualStatus.CACHED.value]
                ),
            )
            .order_by(IndividualRow.generation, IndividualRow.index)
            .execution_options(yield_per=chunk)
        )
        for generation, index, fitness, operator, measures, genome_hash in result:
            yield {
                "generation": generation,
                "index": index,
                "fitness": fitness,
                "operator": operator,
                "measures": measures or {},
                "genome_hash": genome_hash,
            }


def genomes(db: Database, run_id: int, where: list[tuple[int, int]]) -> dict[tuple[int, int], Any]:
    """The genomes (stored JSON) of the individuals at these (generation, index)."""
    if not where:
        return {}
    with db.read_session() as session:
        result = session.execute(
            select(IndividualRow.generation, IndividualRow.index, IndividualRow.genome).where(
                IndividualRow.run_id == run_id,
                tuple_(IndividualRow.generation, IndividualRow.index).in_(where),
            )
        )
        return {(g, i): genome for g, i, genome in result}
