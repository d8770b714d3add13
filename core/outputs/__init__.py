"""Outputs: figures, pictures, replays and exports (VXA, glTF, STL) of runs and robots."""
