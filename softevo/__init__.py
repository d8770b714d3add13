"""softevo: evolve modular soft crawling robots. The `softevo` command lives in `softevo.cli`."""

__version__ = "0.1.0"
