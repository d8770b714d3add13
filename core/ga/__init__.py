"""The genetic algorithm: pure operators and an ask/tell algorithm on explicit, JSON-able state."""
