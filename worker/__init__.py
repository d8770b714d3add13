"""softevo's RQ worker side: the job that evaluates batches of robots with `core` (later issue)."""
