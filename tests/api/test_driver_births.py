"""The driver keeps every strategy's births one way (issue 50): written with the next write, a
row's commit keeps the next row's, and a successor that breeds a birth other than the stored
one refuses to mix them."""

from __future__ import annotations

import threading

import pytest

from softevo.api import store
from softevo.api.db import Database
from softevo.api.driver import Driving, RunDriver, members
from softevo.api.faults import Faults
from softevo.api.store.driving import GenerationMismatchError
from softevo.core.config import resolve
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import SerialEvaluator
from tests.api.store.test_store import OWNER, REQUEST, driven


def driver(db: Database, run_id: int) -> RunDriver:
    stopping = threading.Event()
    driving = Driving(db, SerialEvaluator(), OWNER, 4, 2, 60.0, stopping, Faults())
    return RunDriver(driving, run_id)


def test_a_successor_finds_the_stored_births_and_refuses_other_ones(db: Database) -> None:
    run_id = driven(db)
    individuals = Evolution.start(resolve(REQUEST)).individuals()
    first = driver(db, run_id)
    assert first.births(0, dict(enumerate(individuals))) == ({}, {})
    assert [item[:2] for item in first.members] == [(0, i) for i in range(len(individuals))]
    first.generation = 0  # the row being evaluated, as `drive` sets it
    first.flush()  # what a write keeps
    assert not first.members
    successor = driver(db, run_id)
    assert successor.births(0, dict(enumerate(individuals))) == ({}, {})
    assert not successor.members  # stored already: not written twice
    other = Evolution.start(resolve({**REQUEST, "seed": 2})).individuals()
    with pytest.raises(GenerationMismatchError, match="birth 0 of generation 0"):
        driver(db, run_id).births(0, dict(enumerate(other)))
    assert members(individuals)[0]["genome_hash"] == individuals[0].genome.hash
    stored = store.births.stored_births(db, run_id, 0)
    assert [stored[(0, i)][0] for i in range(len(individuals))] == [
        item.genome.hash for item in individuals
    ]
