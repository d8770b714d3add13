"""FastAPI dependencies: settings, the database, the coordinator and the token check."""

from __future__ import annotations

import hmac
from typing import Annotated

from fastapi import Depends, HTTPException, Request, status
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer

from softevo.api.coordinator import Coordinator
from softevo.api.db import Database
from softevo.api.settings import Settings


def get_settings(request: Request) -> Settings:
    return request.app.state.settings


def get_db(request: Request) -> Database:
    return request.app.state.db


def get_coordinator(request: Request) -> Coordinator:
    return request.app.state.coordinator


_bearer = HTTPBearer(auto_error=False, description="needed when SOFTEVO_API_TOKEN is set")


def require_token(
    settings: Annotated[Settings, Depends(get_settings)],
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> None:
    """State-changing requests need `Authorization: Bearer <token>` when a token is set."""
    expected = settings.api_token
    if not expected:
        return
    if credentials is None:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "missing bearer token (Authorization: Bearer <token>)",
            headers={"WWW-Authenticate": "Bearer"},
        )
    if not hmac.compare_digest(credentials.credentials.encode(), expected.encode()):
        raise HTTPException(status.HTTP_403_FORBIDDEN, "wrong bearer token")


def is_trusted(request: Request, settings: Annotated[Settings, Depends(get_settings)]) -> bool:
    """Whether the caller may see internals: no token is configured, or it sent the right one.
    (Read from the header, not as a security scheme: the route stays open to anyone.)"""
    expected = settings.api_token
    if not expected:
        return True
    scheme, _, token = request.headers.get("authorization", "").partition(" ")
    return scheme.lower() == "bearer" and hmac.compare_digest(token.encode(), expected.encode())


SettingsDep = Annotated[Settings, Depends(get_settings)]
TrustedDep = Annotated[bool, Depends(is_trusted)]
DatabaseDep = Annotated[Database, Depends(get_db)]
CoordinatorDep = Annotated[Coordinator, Depends(get_coordinator)]
TokenDep = Depends(require_token)
