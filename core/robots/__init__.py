"""Robots: the voxel lattice, bodies, robot files, simulation settings, terrain and tasks,
and genomes with the encodings that build bodies from them (voxel, spring, voxel-phase, cppn)."""
