"""softevo's service: FastAPI app, persistence and the GA coordinator (built in a later issue)."""
