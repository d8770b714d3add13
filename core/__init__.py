"""softevo's core (installed as `softevo.core`), in rooms that say what they hold, each
importing only the rooms above it (an import-linter `layers` contract in pyproject.toml; the
cppn encoding's mutate and mate hooks, which call its NEAT operators in search, are the one
exception it names):

    robots/    the voxel lattice, bodies, robot files, simulation settings, terrain, tasks, genomes
               and their encodings
    physics/   the numba mass-spring engine, and robot files simulated into records of measures
    search/    the strategies (ask/tell on JSON state), the generation step and `Evolution`
    outputs/   figures, pictures, replays and exports (VXA, glTF, STL)

and, shared by them: `config` (a run's configuration, which reads search's strategies),
`evaluator` (the one interface between search and physics), `objectives`, `limits`, `nulls`
and `status`.

Pure Python and numba: no database, no Redis, no web framework (import-linter's contract in
pyproject.toml).
"""
