"""Search: strategies as ask/tell on explicit, JSON-able state (one module per algorithm, found
through the `softevo.strategies` entry points), their operators, archive and Pareto tools, and
births (`cohort`), the unit of ask/tell, and the one step (`stream`, run by `generation`) that
runs any of them."""
