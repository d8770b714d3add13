"""Closed reads (SOFTEVO_PROTECT_READS=1): every GET needs the API token too, for a service on a
shared network. Off by default, where reads are open by design and only writes need the token.

The token comes as `Authorization: Bearer <token>` (the Python client, curl) or as the
`softevo_token` cookie, which the dashboard sets from its token field, because its pictures,
links and event stream are fetched by the browser, which adds no header to them. A cookie opens
reads only: a write needs the header, so another site cannot make a browser write (CSRF).

Open to anyone even then: `/healthz` (a load balancer's probe), and the dashboard's page, files
and the API's own description (`/`, `/static/...`, `/docs`, `/openapi.json`), which hold no data
and are where a user types the token.
"""

from __future__ import annotations

import hmac
import json
from urllib.parse import unquote

from starlette.requests import cookie_parser
from starlette.types import ASGIApp, Receive, Scope, Send

#: Paths that stay open, and the prefix under which the dashboard's files are.
OPEN_PATHS = frozenset({"/healthz", "/", "/docs", "/openapi.json"})
OPEN_PREFIX = "/static/"
#: The cookie the dashboard keeps the token in.
COOKIE = "softevo_token"
READ_METHODS = frozenset({"GET", "HEAD"})


class ReadTokenMiddleware:
    """401 for a read without the token, 403 for a wrong one; writes are left to the routes'
    own check (`softevo.api.deps.require_token`)."""

    def __init__(self, app: ASGIApp, token: str) -> None:
        self.app = app
        self.token = token.encode()

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        path = scope.get("path", "")
        if (
            scope["type"] != "http"
            or scope["method"] not in READ_METHODS
            or path in OPEN_PATHS
            or path.startswith(OPEN_PREFIX)
        ):
            await self.app(scope, receive, send)
            return
        sent = sent_token(scope)
        if sent is None:
            await _refuse(
                send,
                401,
                "reads need the bearer token on this service "
                "(SOFTEVO_PROTECT_READS): Authorization: Bearer <token>",
            )
        elif not hmac.compare_digest(sent.encode(), self.token):
            await _refuse(send, 403, "wrong bearer token")
        else:
            await self.app(scope, receive, send)


def sent_token(scope: Scope) -> str | None:
    """The bearer token of the request's Authorization header, else its cookie's; None: neither."""
    headers = {name: value for name, value in scope.get("headers", [])}
    scheme, _, token = headers.get(b"authorization", b"").decode("latin-1").partition(" ")
    if scheme.lower() == "bearer" and token:
        return token.strip()
    cookie = cookie_parser(headers.get(b"cookie", b"").decode("latin-1")).get(COOKIE)
    return unquote(cookie) if cookie else None  # the dashboard writes it URI-encoded


async def _refuse(send: Send, status: int, detail: str) -> None:
    body = json.dumps({"detail": detail}).encode()
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
    if status == 401:
        headers.append((b"www-authenticate", b"Bearer"))
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": body})
