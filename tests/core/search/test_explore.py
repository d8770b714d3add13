"""Issue 51: exploring variation (gene-by-gene mutation, repeats re-drawn) for NSGA-II, AFPO and
the GA, the options new runs get, the budget in simulations and the normalised hypervolume."""

from __future__ import annotations

import numpy as np
import pytest

from softevo.core.config import ConfigError, resolve
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.robots.encoding_registry import make_encoding
from softevo.core.search import operators, pareto
from softevo.core.search.configured import StrategySettings
from softevo.core.search.state import Individual
from softevo.core.search.variation import explore_children, explore_mutants, gene_rate
from tests.core.search.test_nsga2_afpo import Run

ENCODING = make_encoding("voxel", (3, 3, 2))
CONFIG = StrategySettings.model_validate({"algorithm": "nsga2"})


def population(n: int, seed: int) -> list[Individual]:
    rng = np.random.default_rng(seed)
    return [Individual(ENCODING.random(rng), "random") for _ in range(n)]


def changed(child: Individual, parent: Individual) -> int:
    a, b = np.array(child.genome.discrete), np.array(parent.genome.discrete)
    return int((a != b).sum() + (np.array(child.genome.real) != parent.genome.real).sum())


def test_mutants_change_mutated_genes_on_average_and_never_repeat_a_parent() -> None:
    parents = population(100, 1)
    rng = np.random.default_rng(2)
    chosen = list(range(100)) * 10
    children = explore_mutants(CONFIG, ENCODING, parents, chosen, 2.0, rng)
    counts = [changed(child, parents[i]) for child, i in zip(children, chosen, strict=True)]
    # 2 expected; 2 / (1 - P(no change)) = 2.28 once children that change nothing are re-drawn
    assert 2.1 < np.mean(counts) < 2.5
    assert min(counts) >= 1
    hashes = [child.genome.hash for child in children]
    assert len(set(hashes)) == len(hashes)  # a repeat of an earlier child is re-drawn too
    assert gene_rate(ENCODING, 2.0) == pytest.approx(2.0 / (18 + 3))


def test_children_of_one_genome_are_all_new_and_the_same_for_one_seed() -> None:
    """A population of copies (the collapse): every child still a genome not met before."""
    parents = population(1, 3) * 6
    mates = np.zeros((4, 2), dtype=np.int64)
    first = explore_children(CONFIG, ENCODING, parents, mates, 7, 1.0, np.random.default_rng(5))
    again = explore_children(CONFIG, ENCODING, parents, mates, 7, 1.0, np.random.default_rng(5))
    assert [c.genome.hash for c in first] == [c.genome.hash for c in again] and len(first) == 7
    assert parents[0].genome.hash not in {c.genome.hash for c in first}
    assert len({c.genome.hash for c in first}) == 7


def test_mutate_real_each_steps_about_rate_of_the_genes_within_bounds() -> None:
    bounds = np.array([[0.0, 1.0]] * 1000)
    genes = np.full(1000, 0.5)
    stepped = operators.mutate_real_each(genes, bounds, 0.1, 0.5, np.random.default_rng(1))
    assert 60 < int((stepped != genes).sum()) < 140
    assert stepped.min() >= 0.0 and stepped.max() <= 1.0


@pytest.mark.parametrize("algorithm", ["nsga2", "afpo", "ga"])
def test_explore_keeps_more_diversity_than_the_paper_operators(algorithm: str) -> None:
    paper = Run(1, algorithm=algorithm, options={"variation": "paper"})
    explore = Run(1, algorithm=algorithm, options={"variation": "explore"})
    paper.finish(), explore.finish()
    assert explore.finish() != paper.finish()
    new = [stats.evaluations for stats in explore.state.history]
    assert sum(new) >= sum(stats.evaluations for stats in paper.state.history)


def test_steady_state_explores_births_that_repeat_no_member_and_keeps_its_curve() -> None:
    """Steady-state with options variation explore: more genomes simulated than the paper's
    operators give (few children repeat a member or a birth in flight), the same curve for the
    same seed, and the paper's arithmetic still the default."""

    def curve(options: dict) -> list[dict]:
        request = {
            "algorithm": "steady-state",
            "preset": "quick",
            "shape": [2, 2, 2],
            "population": 8,
            "generations": 6,
            "sim": {"duration": 0.5, "settle_time": 0.2},
            "options": options,
        }
        evolution = Evolution.start(resolve(request))
        evolution.run(SerialEvaluator())
        return evolution.curve()

    paper, explore = curve({}), curve({"variation": "explore"})
    assert curve({"variation": "paper"}) == paper
    assert curve({"variation": "explore"}) == explore != paper
    simulated = [sum(row["evaluations"] for row in rows[1:]) for rows in (paper, explore)]
    assert simulated[1] > simulated[0]  # the first row is random in both


def test_new_runs_explore_and_stored_configs_keep_their_variation() -> None:
    new = resolve({"preset": "quick", "algorithm": "nsga2"}, new=True)
    assert new.options == {"variation": "explore"}
    stored = resolve({"preset": "quick", "algorithm": "nsga2"})  # a config stored before
    assert stored.options == {} and "options" not in stored.to_json()
    assert resolve(new.to_json()).options == {"variation": "explore"}  # stored, then read
    asked = resolve(
        {"preset": "quick", "algorithm": "afpo", "options": {"variation": "paper"}}, new=True
    )
    assert asked.options == {"variation": "paper"}
    assert resolve({"preset": "quick"}, new=True).options == {}  # the GA: as it was


@pytest.mark.parametrize("algorithm", ["ga", "steady-state"])
def test_max_simulations_ends_the_run_at_the_first_row_reaching_it(algorithm: str) -> None:
    request = {
        "algorithm": algorithm,
        "preset": "quick",
        "shape": [2, 2, 2],
        "population": 6,
        "generations": 9,
        "sim": {"duration": 0.5, "settle_time": 0.2},
        "max_simulations": 14,
    }
    evolution = Evolution.start(resolve(request))
    evolution.run(SerialEvaluator())
    counts = [row["evaluations"] for row in evolution.curve()]
    assert sum(counts[:-1]) < 14 <= sum(counts) and len(counts) < 9
    assert "max_simulations" not in resolve({"preset": "quick"}).to_json()  # hashes as before
    with pytest.raises(ConfigError, match=r"^max_simulations: .*greater than or equal to 1"):
        resolve({"preset": "quick", "max_simulations": 0})


def test_normalised_hypervolume_weighs_both_objectives_alike() -> None:
    ideal, nadir = np.array([1.0, -10.0]), np.array([0.0, -1000.0])
    assert pareto.normalised_hypervolume(np.array([[1.0, -10.0]]), ideal, nadir) == 1.0
    corner = pareto.normalised_hypervolume(np.array([[0.0, -1000.0]]), ideal, nadir)
    assert corner == pytest.approx(0.01 / 1.21)  # the nadir itself: only the margin's box
    fast = pareto.normalised_hypervolume(np.array([[1.0, -1000.0]]), ideal, nadir)
    cheap = pareto.normalised_hypervolume(np.array([[0.0, -10.0]]), ideal, nadir)
    assert fast == pytest.approx(cheap)  # the two ends count the same, whatever the units
    with pytest.raises(ValueError, match="ideal must be finite and above nadir"):
        pareto.normalised_hypervolume(np.array([[1.0, 1.0]]), nadir, ideal)
