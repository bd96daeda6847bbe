"""Reading and writing results: output directories, tables, trajectories."""
