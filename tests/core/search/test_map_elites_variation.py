"""MAP-Elites' own variation (issue 38): the per-gene label mutation and the iso-line step, the
options that choose them, and default options that breed exactly as map-elites did before."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest

from softevo import library
from softevo.core.config import ConfigError, resolve
from softevo.core.robots.encodings import Variation, VoxelEncoding
from softevo.core.robots.genome import Genome
from softevo.core.search.archive import Archive
from softevo.core.search.configured import describe_strategies, make_strategy
from softevo.core.search.map_elites import spread_random
from softevo.core.search.operators import iso_line, mutate_each
from softevo.core.search.state import Individual, StrategyState

ALPHABET = np.array([5] * 40 + [1] * 4 + [2] * 6)
BOUNDS = np.array([[-1.0, 1.0], [-2.0, 2.0], [0.0, 10.0]])
#: A tiny map-elites run (crossover, mutation and an immigrant every generation), and the
#: SHA-256 of its curve and archive computed with the code before MAP-Elites had options.
PINNED_RUN = {
    "preset": "quick",
    "algorithm": "map-elites",
    "descriptors": ["voxels", "actuated"],
    "bins": [4, 4],
    "population": 6,
    "generations": 3,
    "seed": 3,
    "sim": {"profile": "paper", "duration": 1.0, "settle_time": 0.5},
}
PINNED_CURVE = "02371943c7bdcf2467f562cb62459aa98458c9598cac3d5f08ed29b4c8d4dafa"
PINNED_ARCHIVE = "29cf7cc5db791b4850b450d02dc2a2767455ed727f10dc68a6dbb7f5463c1845"
MUTATION = {"variation": "mutation", "label_rate": 0.1}


def sha256(value: object) -> str:
    return hashlib.sha256(json.dumps(value, sort_keys=True).encode()).hexdigest()


def test_mutate_each_changes_genes_at_its_rate_within_their_alphabets() -> None:
    genes = np.random.default_rng(0).integers(0, ALPHABET)
    children = [mutate_each(genes, ALPHABET, 0.3, np.random.default_rng(s)) for s in range(200)]
    changed = np.array([child != genes for child in children])
    assert all(((c >= 0) & (c < ALPHABET)).all() for c in children)
    assert not changed[:, ALPHABET == 1].any()  # a one-value gene never changes
    assert changed[:, ALPHABET > 1].mean() == pytest.approx(0.3, abs=0.03)
    assert (mutate_each(genes, ALPHABET, 0.0, np.random.default_rng(1)) == genes).all()
    assert (mutate_each(genes, ALPHABET, 1.0, np.random.default_rng(1)) != genes)[
        ALPHABET > 1
    ].all()  # every changeable gene, each to another value
    again = mutate_each(genes, ALPHABET, 0.3, np.random.default_rng(5))
    assert (again == children[5]).all()  # the generator decides everything


def test_iso_line_steps_along_the_line_through_two_elites_within_bounds() -> None:
    x, y = np.array([0.2, -1.0, 3.0]), np.array([0.6, 1.0, 5.0])
    # without the isotropic term the child lies on the line x + t (y - x), t ~ N(0, sigma_line)
    ts = []
    for seed in range(300):
        child = iso_line(x, y, np.array([[-9.0, 9.0]] * 3), 0.0, 0.2, np.random.default_rng(seed))
        t = (child - x) / (y - x)
        assert t == pytest.approx(np.full(3, t[0]))
        ts.append(t[0])
    assert np.std(ts) == pytest.approx(0.2, rel=0.15)
    # the definition, draw by draw: N(0, I) for the isotropic step first, then one N(0, 1)
    rng, copy = np.random.default_rng(7), np.random.default_rng(7)
    found = iso_line(x, y, BOUNDS, 0.05, 0.3, rng)
    span = BOUNDS[:, 1] - BOUNDS[:, 0]
    expected = x + copy.normal(0.0, 1.0, 3) * 0.05 * span + copy.normal(0.0, 1.0) * 0.3 * (y - x)
    assert found == pytest.approx(np.clip(expected, BOUNDS[:, 0], BOUNDS[:, 1]))
    wild = [iso_line(x, y, BOUNDS, 3.0, 5.0, np.random.default_rng(s)) for s in range(50)]
    assert all(((BOUNDS[:, 0] <= w) & (w <= BOUNDS[:, 1])).all() for w in wild)
    assert len(iso_line(np.empty(0), np.empty(0), np.empty((0, 2)), 0.1, 0.2, rng)) == 0


@pytest.mark.parametrize(
    ("options", "field"),
    [
        ({"label_rate": 0.1}, "options.label_rate: applies to variation 'mutation' only"),
        ({"variation": "mutation", "label_rate": 1.5}, "options.label_rate"),
        ({"variation": "mutation", "line_sigma": 0.3}, "options.line_sigma: applies to real"),
        ({"variation": "mutation", "real": "line"}, "options.real"),
        ({"variation": "walk"}, "options.variation"),
        ({"variation": "mutation", "sigma": -1.0}, "options.sigma"),
    ],
)
def test_bad_options_are_refused_naming_the_option(options: dict, field: str) -> None:
    with pytest.raises(ConfigError, match=field.replace(".", r"\.").replace("(", r"\(")):
        resolve({"preset": "quick", "algorithm": "map-elites", "options": options})


def test_the_options_are_listed_with_the_strategy() -> None:
    listed = {entry["name"]: entry for entry in describe_strategies()}
    fields = listed["map-elites"]["options"]["properties"]
    assert {"variation", "label_rate", "real", "sigma", "line_sigma"} <= set(fields)
    assert fields["variation"]["default"] == "crossover"


def test_default_options_breed_as_map_elites_did_before_they_existed() -> None:
    result = library.evolve(PINNED_RUN, workers=1)
    assert sha256(result.curve) == PINNED_CURVE
    assert sha256(result.archive) == PINNED_ARCHIVE
    default, state = elites_state({})
    explicit, _ = elites_state({"variation": "crossover"})
    assert default.ask(state) == explicit.ask(state)


def elites_state(options: dict) -> tuple[object, StrategyState]:
    """A map-elites strategy on 3x3x2 and a state whose archive holds 5 random elites."""
    config = resolve({**PINNED_RUN, "shape": [3, 3, 2], "options": options})
    encoding = VoxelEncoding((3, 3, 2))
    rng = np.random.default_rng(11)
    archive = Archive(("voxels", "actuated"), (4, 4))
    for i in range(5):
        archive.add((i / 5, i / 5), float(i), 0, i, encoding.random(rng))
    previous = [Individual(encoding.random(rng), "random") for _ in range(6)]
    state = StrategyState(
        seed=4, generation=1, previous=previous, previous_fitness=[0.0] * 6, archive=archive
    )
    return make_strategy(config.strategy_settings(), encoding), state


@pytest.mark.parametrize("real", ["gaussian", "iso-line"])
def test_mutation_only_children_are_mutants_of_elites(real: str) -> None:
    strategy, state = elites_state({**MUTATION, "real": real})
    children = strategy.ask(state)
    assert children == strategy.ask(state)  # one state, one set of children
    elites = {elite.genome.discrete for elite in state.archive.ordered()}
    bred = children[:-1]  # the last is the quick preset's immigrant
    assert [c.operator for c in bred] == [f"elite-{'mutation' if real == 'gaussian' else real}"] * 5
    assert children[-1].operator == "immigrant"
    for child in bred:  # a few labels from an elite's, no crossover's long runs
        nearest = min(
            sum(a != b for a, b in zip(child.genome.discrete, e, strict=True)) for e in elites
        )
        assert nearest <= 6
        assert all(-1.0 <= a <= 1.0 for a in child.genome.real[:1])


def test_an_encoding_with_its_own_operators_mutates_its_genomes() -> None:
    strategy, state = elites_state(MUTATION)
    seen: list[Genome] = []

    class Own(Variation):  # what a CPPN encoding brings (NEAT mutations)
        def mate(self, rates, first, second, rng):  # never called here
            raise AssertionError("map-elites with mutation only mutates")

        def mutate(self, rates, genome, rng):
            seen.append(genome)
            return genome

    strategy.encoding.variation = Own()  # this instance alone
    children = strategy.ask(state)
    assert len(seen) == 5 and {c.operator for c in children[:-1]} == {"elite-copy+mutation"}


def test_a_preset_s_options_stay_with_its_algorithm() -> None:
    preset = resolve({"preset": "map-elites"})
    assert preset.options == {"random": "spread"}
    assert resolve({"preset": "map-elites", "algorithm": "ga"}).options == {}
    assert resolve({"preset": "paper-voxel", "algorithm": "map-elites"}).options == {}


def test_spread_random_genomes_draw_bodies_of_every_size() -> None:
    encoding = VoxelEncoding((4, 4, 4))
    spread = [spread_random(encoding, np.random.default_rng(s)) for s in range(200)]
    uniform = [encoding.random(np.random.default_rng(s)) for s in range(200)]
    assert spread_random(encoding, np.random.default_rng(3)) == spread[3]
    for genome in spread:
        encoding.check(genome)  # labels in the alphabet, real genes within their bounds
        assert all(
            low <= g <= high
            for g, (low, high) in zip(genome.real, encoding.real_bounds, strict=True)
        )
    filled = [np.mean(np.array(g.discrete) != 0) for g in spread]
    assert min(filled) < 0.4 and max(filled) > 0.95  # uniform labels: about 0.8 every time
    assert np.std(filled) > 3 * np.std([np.mean(np.array(g.discrete) != 0) for g in uniform])


def test_spread_random_is_asked_for_generation_0_and_the_immigrants() -> None:
    strategy, state = elites_state({"random": "spread"})
    uniform, _ = elites_state({})
    first = strategy.first(np.random.default_rng(2))
    assert first != uniform.first(np.random.default_rng(2))
    assert [i.operator for i in first] == ["random"] * 6
    children, before = strategy.ask(state), uniform.ask(state)
    assert children[:-1] == before[:-1] and children[-1] != before[-1]  # only the immigrant
