"""softevo's RQ side (installed as `softevo.worker`): the job that evaluates a batch of robots
with `softevo.core`, `softevo worker`, and the RQ evaluator the API enqueues through."""
