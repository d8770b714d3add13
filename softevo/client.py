"""A Python client of the softevo service (`softevo serve`, docker compose): start runs and
sweeps, wait for them, read their curves, individuals and best robots.

It speaks only HTTP (httpx and the standard library, no numba or physics: import-linter's
contract in pyproject.toml), so a notebook on a laptop can drive a service elsewhere::

    from softevo.client import Client

    with Client("http://127.0.0.1:8000", token=None) as client:
        run = client.run(preset="quick", seed=1, population=8, generations=3)
        run.wait()
        print(run.curve()[-1]["best_so_far"], run.best()["format"])

Every answer of 400 or more is an `APIError` carrying the API's own message (its `detail`); a
service that cannot be reached is an `UnreachableError`. docs/python.md has a worked example.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from typing import Any, Self, TextIO

try:
    import httpx
except ModuleNotFoundError:  # `pip install softevo` is the CLI alone
    raise ModuleNotFoundError(
        "softevo.client needs httpx, one of the service's packages: pip install 'softevo[service]'"
    ) from None

#: The statuses a run does not leave (softevo.core.status.FINAL, named here so that this module
#: loads nothing of the engine; tests/softevo/test_client.py checks that they agree).
FINAL = frozenset({"completed", "failed", "cancelled"})


class ClientError(Exception):
    """Anything this client raises about the service."""


class UnreachableError(ClientError):
    """The service did not answer: not started, wrong URL, network down or too slow."""


class APIError(ClientError):
    """The service answered 400 or more; `message` is its `detail` made readable (a 422 names
    the field), `status` the HTTP status."""

    def __init__(self, status: int, message: str, method: str, path: str) -> None:
        super().__init__(f"{method} {path} answered {status}: {message}")
        self.status, self.message, self.method, self.path = status, message, method, path


def _message(response: httpx.Response) -> str:
    """The API's `detail`: a string, or FastAPI's list of {loc, msg}, one `loc: msg` per item
    (the body's fields as `a.b`, without the leading `body`)."""
    try:
        detail = response.json()["detail"]
    except (ValueError, KeyError, TypeError):
        return response.text[:500] or response.reason_phrase
    if isinstance(detail, str):
        return detail
    if not isinstance(detail, list):
        return str(detail)
    parts = []
    for item in detail:
        if not isinstance(item, dict):
            parts.append(str(item))
            continue
        loc = [str(p) for p in item.get("loc", [])]
        field = ".".join(loc[1:] if loc[:1] == ["body"] else loc)
        message = str(item.get("msg", ""))
        named = not field or message.startswith(f"{field}:")
        parts.append(message if named else f"{field}: {message}")
    return "; ".join(parts)


class Client:
    """One service: `url` like http://127.0.0.1:8000; `token` is sent as `Authorization:
    Bearer <token>` with every request (what a service with SOFTEVO_API_TOKEN asks of every
    POST, and with SOFTEVO_PROTECT_READS=1 of every GET too)."""

    def __init__(self, url: str, token: str | None = None, timeout: float = 60.0) -> None:
        self.url = url.rstrip("/")
        headers = {"Authorization": f"Bearer {token}"} if token else {}
        self.http = httpx.Client(base_url=self.url, headers=headers, timeout=timeout)

    def request(self, method: str, path: str, **kwargs: Any) -> Any:
        """The decoded JSON answer of one request; APIError or UnreachableError otherwise."""
        try:
            response = self.http.request(method, path, **kwargs)
        except httpx.TransportError as error:
            raise UnreachableError(f"{method} {self.url}{path}: {error}") from error
        if response.status_code >= 400:
            raise APIError(response.status_code, _message(response), method, path)
        return response.json()

    def get(self, path: str, **params: Any) -> Any:
        return self.request("GET", path, params=params or None)

    def post(self, path: str, body: dict[str, Any] | None = None) -> Any:
        return self.request("POST", path, json=body if body is not None else {})

    # -- runs and sweeps ---------------------------------------------------------------------

    def run(self, **config: Any) -> Run:
        """Queue a run (POST /runs): a `preset` plus any setting to override, e.g.
        `client.run(preset="quick", seed=1, population=8, generations=3, sim={"duration": 1})`."""
        data = self.post("/runs", config)
        return Run(self, int(data["id"]), data)

    def sweep(self, **config: Any) -> Sweep:
        """Queue a sweep (POST /sweeps): a base config over `shapes` and `seeds`, or `tasks`."""
        data = self.post("/sweeps", config)
        return Sweep(self, int(data["id"]), data)

    def get_run(self, run_id: int) -> Run:
        """A handle on an existing run (nothing is asked until a method is called)."""
        return Run(self, run_id)

    def get_sweep(self, sweep_id: int) -> Sweep:
        return Sweep(self, sweep_id)

    def runs(self, status: str | None = None, page: int = 200) -> Iterator[dict[str, Any]]:
        """Every run the service holds (GET /runs), newest first, `page` to a request."""
        offset = 0
        while True:
            params: dict[str, Any] = {"offset": offset, "limit": page}
            if status is not None:
                params["status"] = status
            answer = self.get("/runs", **params)
            yield from answer["items"]
            offset += len(answer["items"])
            if not answer["items"] or offset >= answer["total"]:
                return

    def presets(self) -> list[dict[str, Any]]:
        return self.get("/presets")

    def health(self) -> dict[str, Any]:
        """GET /healthz, whatever its status (a 503 says which part is down)."""
        try:
            return self.http.get("/healthz").json()
        except httpx.TransportError as error:
            raise UnreachableError(f"GET {self.url}/healthz: {error}") from error

    def close(self) -> None:
        self.http.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class _Line:
    """One progress line: rewritten in place on a terminal, a new line per change elsewhere."""

    def __init__(self, stream: TextIO) -> None:
        self.stream, self.last = stream, ""
        self.tty = stream.isatty()

    def show(self, text: str) -> None:
        if text == self.last:
            return
        if self.tty:
            self.stream.write(f"\r{text:<{len(self.last)}}")
        else:
            self.stream.write(text + "\n")
        self.stream.flush()
        self.last = text

    def end(self) -> None:
        if self.tty and self.last:
            self.stream.write("\n")
            self.stream.flush()


def _poll(
    step: Any, done: Any, line: Any, progress: bool, poll: float, timeout: float | None
) -> dict[str, Any]:
    """Call `step()` until `done(answer)`, showing `line(answer)`; TimeoutError past `timeout`."""
    deadline = None if timeout is None else time.monotonic() + timeout
    shown = _Line(sys.stderr) if progress else None
    try:
        while True:
            answer = step()
            if shown is not None:
                shown.show(line(answer))
            if done(answer):
                return answer
            if deadline is not None and time.monotonic() > deadline:
                raise TimeoutError(f"{line(answer)}: still going after {timeout:g} s")
            time.sleep(poll)
    finally:
        if shown is not None:
            shown.end()


class Run:
    """One run on the service. `data` is the API's last answer about it (GET /runs/{id})."""

    def __init__(self, client: Client, run_id: int, data: dict[str, Any] | None = None) -> None:
        self.client, self.id = client, run_id
        self.data: dict[str, Any] = data or {}  # {}: not read yet

    def __repr__(self) -> str:
        status = self.data["status"] if self.data else "?"
        return f"Run({self.id}, {status})"

    def status(self) -> dict[str, Any]:
        """The run now: status, progress (generation of generations, best fitness, ETA)."""
        self.data = self.client.get(f"/runs/{self.id}")
        return self.data

    def _line(self, data: dict[str, Any]) -> str:
        p = data["progress"]
        best = "" if p["best_fitness"] is None else f", best {p['best_fitness']:.4g}"
        counter = f"generation {p['generation']}/{p['generations']}"
        return f"run {self.id}: {counter}{best} ({data['status']})"

    def wait(
        self, progress: bool = True, poll: float = 0.5, timeout: float | None = None
    ) -> dict[str, Any]:
        """Until the run is completed, failed or cancelled (its last status, whichever);
        `progress` prints a generation counter on stderr."""
        return _poll(
            self.status, lambda d: d["status"] in FINAL, self._line, progress, poll, timeout
        )

    def curve(self) -> list[dict[str, Any]]:
        """One dict per committed generation: best, mean, median, min, best_so_far, ..."""
        return self.client.get(f"/runs/{self.id}/curve")["generations"]

    def individuals(self, generation: int | None = None) -> list[dict[str, Any]]:
        """Every individual (all pages), or one generation's: fitness, `measures` (what its
        simulation measured, by name; docs/physics.md), status, parents, ..."""
        items: list[dict[str, Any]] = []
        while True:
            params: dict[str, Any] = {"offset": len(items), "limit": 5000}
            if generation is not None:
                params["generation"] = generation
            page = self.client.get(f"/runs/{self.id}/individuals", **params)
            items += page["items"]
            if not page["items"] or len(items) >= page["total"]:
                return items

    def individual(self, number: int) -> dict[str, Any]:
        """Individual `number` (generation * population + index) with its genome and robot."""
        return self.client.get(f"/runs/{self.id}/individuals/{number}")

    def best(self) -> dict[str, Any]:
        """The fastest robot so far as a robot file (softevo.robot/1): `softevo simulate` it."""
        return self.client.get(f"/runs/{self.id}/best")

    def replay(self, fps: float = 30.0) -> dict[str, Any]:
        """The best robot's mass positions over time and its springs (simulated on request)."""
        return self.client.get(f"/runs/{self.id}/best/replay", fps=fps)

    def archive(self, robots: bool = False) -> dict[str, Any]:
        """A run with descriptors: its MAP-Elites archive (every filled cell, coverage,
        QD-score; each elite's robot file with `robots`); APIError 404 for a run without."""
        return self.client.get(f"/runs/{self.id}/archive", robots=str(robots).lower())

    def front(self, robots: bool = False) -> dict[str, Any]:
        """A run with objectives: its Pareto front so far (every non-dominated individual with
        its measures, generation and index; each one's robot file with `robots`); APIError 404
        for a run without."""
        return self.client.get(f"/runs/{self.id}/front", robots=str(robots).lower())

    def cancel(self) -> dict[str, Any]:
        """Stop the run now, keeping its results; APIError 409 if it has already stopped."""
        self.data = self.client.post(f"/runs/{self.id}/cancel")
        return self.data


class Sweep:
    """One sweep: runs over bounding boxes (or tasks) and seeds. `data` is GET /sweeps/{id}."""

    def __init__(self, client: Client, sweep_id: int, data: dict[str, Any] | None = None) -> None:
        self.client, self.id = client, sweep_id
        self.data: dict[str, Any] = data or {}  # {}: not read yet

    def __repr__(self) -> str:
        status = self.data["status"] if self.data else "?"
        return f"Sweep({self.id}, {status})"

    def status(self) -> dict[str, Any]:
        """Per box (and task): run ids, statuses, best fitness mean, spread, min and max."""
        self.data = self.client.get(f"/sweeps/{self.id}")
        return self.data

    @staticmethod
    def _statuses(data: dict[str, Any]) -> list[str]:
        return [s for box in data["boxes"] for s in box["statuses"]]

    def _line(self, data: dict[str, Any]) -> str:
        statuses = self._statuses(data)
        done = sum(s in FINAL for s in statuses)
        return f"sweep {self.id}: {done}/{len(statuses)} runs done ({data['status']})"

    def wait(
        self, progress: bool = True, poll: float = 1.0, timeout: float | None = None
    ) -> dict[str, Any]:
        """Until every run of the sweep is in a final status; `progress` counts them."""
        return _poll(
            self.status,
            lambda d: all(s in FINAL for s in self._statuses(d)),
            self._line,
            progress,
            poll,
            timeout,
        )

    def runs(self) -> list[Run]:
        """A handle per run, box by box, seed by seed."""
        data = self.data or self.status()
        return [Run(self.client, i) for box in data["boxes"] for i in box["run_ids"]]

    def curves(self) -> dict[int, list[dict[str, Any]]]:
        """Every run's learning curve, by run id."""
        return {run.id: run.curve() for run in self.runs()}
