"""Alembic migrations of softevo's database (a package so they ship with the install)."""
