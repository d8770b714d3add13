"""Search: strategies as ask/tell on explicit, JSON-able state (one module per algorithm, found
through the `softevo.strategies` entry points), their operators, archive and Pareto tools, and
the one generation step (`generation`, `stream`) that runs any of them."""
