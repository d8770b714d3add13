"""softevo's core (installed as `softevo.core`): voxel robots and robot files, the numba
mass-spring engine, genome encodings, the genetic algorithm and its baselines, evaluators,
metrics and figures.

Pure Python and numba: no database, no Redis, no web framework (import-linter's contract in
pyproject.toml).
"""
