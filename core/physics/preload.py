"""Importing this module loads the physics kernels. It is the fork server's preload
(`evaluation.pool_context`): every pool process is forked from a process that already holds
them, so a pool starts in a fraction of a second instead of each process importing numba and
loading the kernels again."""

from softevo.core.physics.evaluation import warm_up

warm_up()
