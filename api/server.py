"""How `softevo serve` runs uvicorn: deadlines on connections that send nothing useful.

uvicorn closes an idle keep-alive connection (`timeout_keep_alive`) but gives a request's head no
deadline: a client that opens a connection and trickles its headers a byte at a time holds it
forever, and a few thousand such clients hold the server's sockets. `HeaderDeadline` is uvicorn's
own h11 protocol with one addition: from the moment a connection could start a request (it opened,
or the previous response finished and data arrived), the whole head (request line and headers)
must arrive within `header_seconds`, or the connection is closed. A streamed response (the event
stream) and a slow body are not affected: the clock stops once the head is in.
"""

from __future__ import annotations

import asyncio
from typing import Any

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

from softevo.api.settings import Settings


class HeaderDeadline(H11Protocol):
    """uvicorn's h11 protocol; a request head must arrive within `header_seconds`."""

    header_seconds: float = 10.0
    _head_timer: asyncio.TimerHandle | None = None

    # uvicorn's protocol is given a Transport, though asyncio types it as a BaseTransport
    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._arm()

    def data_received(self, data: bytes) -> None:
        self._arm()
        super().data_received(data)
        if self.conn.their_state is not h11.IDLE:  # the head is in (or the connection is over)
            self._disarm()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    def _arm(self) -> None:
        """Start the head's clock if a request may begin now and no clock runs."""
        if self._head_timer is None and self.conn.their_state is h11.IDLE:
            self._head_timer = self.loop.call_later(self.header_seconds, self._head_late)

    def _disarm(self) -> None:
        if self._head_timer is not None:
            self._head_timer.cancel()
            self._head_timer = None

    def _head_late(self) -> None:
        self._head_timer = None
        if self.conn.their_state is h11.IDLE and not self.transport.is_closing():
            self.logger.debug("request head not complete after %.1f s: closed", self.header_seconds)
            self.transport.close()

    def on_response_complete(self) -> None:
        super().on_response_complete()
        # the next request's clock starts with its first byte (the keep-alive timeout covers
        # the wait before it); a pipelined request already parsed has its head in
        if self.conn.their_state is not h11.IDLE:
            self._disarm()


def protocol(settings: Settings) -> type[HeaderDeadline]:
    """The protocol class for uvicorn's `http=` with this service's header deadline."""
    return type("SoftevoHTTP", (HeaderDeadline,), {"header_seconds": settings.header_seconds})


def uvicorn_options(settings: Settings) -> dict[str, Any]:
    """uvicorn's connection settings of this service: the header and keep-alive deadlines."""
    return {
        "http": protocol(settings),
        "timeout_keep_alive": settings.keep_alive_seconds,
    }
