"""softevo's core: voxel robots, the numba mass-spring engine, and (later) the genetic algorithm.

Pure Python and numba: no I/O, no database, no Redis, no web framework.
"""
