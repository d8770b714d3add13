"""softevo's service (installed as `softevo.api`): the FastAPI app and dashboard, persistence
(SQLAlchemy) and the coordinator that drives each run generation by generation."""
