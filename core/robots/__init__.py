"""Robots: the voxel lattice, bodies, robot files, terrain and tasks, and the genome
encodings that build bodies (direct, voxel-phase, cppn)."""
