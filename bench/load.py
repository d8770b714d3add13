"""The service under hostile load: `python bench/load.py [--seconds S] [--database D,...]`.

A real `softevo serve` (the in-process pool on every core) while, all at once:
* a run at nearly the largest accepted cost evaluates (8x8x8 paper-voxel, population 670 x 100
  generations, 9.98e12 of the 1e13 spring-steps a run may cost: every core busy simulating),
* 200 clients follow that run's server-sent events,
* 20 clients ask for replays of distinct individuals at distinct frame rates, again and again,
* a probe times `GET /healthz` and `GET /runs/{id}/curve`, ten times a second each.

The probe runs in a process of its own (`--probe loop` puts it in the load generator's event loop
instead, as before): in the loop that reads 200 streams and megabytes of replays, a probe's time
includes the client's own waits for that loop, which is not the server's latency.

Prints the probes' p50 and p99 latency (ms), how the replay requests were answered (200 or 503)
and the server's peak resident memory (VmHWM of the API process, and of its pool processes).
Target (issue 15): p99 under 250 ms for both and peak memory under 1.5 GB.
"""

from __future__ import annotations

import argparse
import asyncio
import multiprocessing
import os
import platform
import statistics
import tempfile
import time
from collections import Counter
from multiprocessing.queues import Queue
from pathlib import Path

import httpx

from softevo.local_service import LocalService, service_env, start_service

POSTGRES = os.environ.get("SOFTEVO_TEST_POSTGRES", "postgresql://postgres@127.0.0.1:5432/test")
# near the default budget (SOFTEVO_MAX_SPRING_STEPS 1e13): 9.98e12 spring-steps, 670 x 100
LARGE = {
    "preset": "paper-voxel",
    "shape": [8, 8, 8],
    "population": 670,
    "generations": 100,
    "seed": 1,
}
SSE_CLIENTS, REPLAY_CLIENTS = 200, 20


def peak_kib(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
    return 0


def children(pid: int) -> list[int]:
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            if int(stat.read_text().rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(stat.parent.name))
        except (OSError, ValueError):
            continue
    return found


async def follow(client: httpx.AsyncClient, run_id: int, stop: asyncio.Event) -> int:
    events = 0
    try:
        async with client.stream("GET", f"/runs/{run_id}/events") as stream:
            async for line in stream.aiter_lines():
                events += line.startswith("event: ")
                if stop.is_set():
                    break
    except httpx.HTTPError:
        pass
    return events


async def replays(
    client: httpx.AsyncClient, run_id: int, k: int, stop: asyncio.Event, answers: Counter[int]
) -> None:
    fps = (1, 2, 5, 10, 15, 20, 30, 60, 120)[k % 9]
    n = k
    while not stop.is_set():  # the first 100 individuals of the first generation
        try:
            response = await client.get(
                f"/runs/{run_id}/individuals/{n}/replay", params={"fps": fps}, timeout=120
            )
            answers[response.status_code] += 1
        except httpx.HTTPError:
            answers[0] += 1
        n = (n + REPLAY_CLIENTS) % 100
        await asyncio.sleep(0.2)


async def probe(
    client: httpx.AsyncClient, path: str, stop: asyncio.Event, out: list[float]
) -> None:
    while not stop.is_set():
        started = time.perf_counter()
        await client.get(path, timeout=60)
        out.append(1e3 * (time.perf_counter() - started))
        await asyncio.sleep(0.1)


def probe_process(url: str, paths: list[str], seconds: float, out: Queue) -> None:
    """The probe in a process of its own: each path timed ten times a second, in turn, over one
    keep-alive connection; puts {path: [ms, ...]} on `out`."""
    times: dict[str, list[float]] = {path: [] for path in paths}
    with httpx.Client(base_url=url, timeout=60) as client:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            for path in paths:
                started = time.perf_counter()
                client.get(path)
                times[path].append(1e3 * (time.perf_counter() - started))
            time.sleep(0.1)
    out.put(times)


async def load(local: LocalService, seconds: float, own_process: bool) -> dict[str, object]:
    limits = httpx.Limits(max_connections=SSE_CLIENTS + REPLAY_CLIENTS + 10)
    async with httpx.AsyncClient(base_url=local.url, limits=limits, timeout=60) as client:
        run_id = (await client.post("/runs", json=LARGE)).json()["id"]
        while (await client.get(f"/runs/{run_id}/individuals")).json()["total"] == 0:
            await asyncio.sleep(0.2)
        stop, answers = asyncio.Event(), Counter[int]()
        healthz: list[float] = []
        curve: list[float] = []
        tasks = [asyncio.create_task(follow(client, run_id, stop)) for _ in range(SSE_CLIENTS)]
        tasks += [
            asyncio.create_task(replays(client, run_id, k, stop, answers))
            for k in range(REPLAY_CLIENTS)
        ]
        paths = ["/healthz", f"/runs/{run_id}/curve"]
        if own_process:
            times: Queue = multiprocessing.get_context("spawn").Queue()
            prober = multiprocessing.get_context("spawn").Process(
                target=probe_process, args=(local.url, paths, seconds, times)
            )
            prober.start()
            await asyncio.sleep(seconds)
            measured = await asyncio.to_thread(times.get, timeout=120)
            prober.join(30)
            healthz, curve = measured[paths[0]], measured[paths[1]]
        else:
            tasks += [
                asyncio.create_task(probe(client, paths[0], stop, healthz)),
                asyncio.create_task(probe(client, paths[1], stop, curve)),
            ]
            await asyncio.sleep(seconds)
        stop.set()
        await client.post(f"/runs/{run_id}/cancel")
        await asyncio.wait(tasks, timeout=120)
    pool = [peak_kib(pid) for pid in children(local.process.pid) if Path(f"/proc/{pid}").exists()]
    api = peak_kib(local.process.pid) / 1024
    return {
        "healthz": healthz,
        "curve": curve,
        "answers": answers,
        "api_mib": api,
        "pool_mib": [kib / 1024 for kib in pool],
    }


def p(values: list[float], q: float) -> float:
    return statistics.quantiles(values, n=100, method="inclusive")[q - 1] if len(values) > 1 else 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--database", default="sqlite,postgres")
    parser.add_argument(
        "--probe",
        choices=["process", "loop"],
        default="process",
        help="time the probes in a process of their own (default) or in the load's event loop",
    )
    args = parser.parse_args()
    machine = f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    print(
        f"# {machine}, {SSE_CLIENTS} SSE clients, {REPLAY_CLIENTS} replay clients, "
        f"{args.seconds:g} s, probe in {args.probe}"
    )
    for name in args.database.split(","):
        with tempfile.TemporaryDirectory() as folder:
            url = f"sqlite:///{Path(folder) / 'load.db'}"
            if name == "postgres":
                from softevo.api.db import Database, scratch_postgres

                scratch = scratch_postgres(POSTGRES, "softevo_load")
                url = scratch.__enter__()
                Database(url).upgrade()
            try:
                with start_service(
                    service_env(database_url=url),
                    Path(folder) / "serve.log",
                    "--log-level",
                    "warning",
                ) as local:
                    result = asyncio.run(load(local, args.seconds, args.probe == "process"))
            finally:
                if name == "postgres":
                    scratch.__exit__(None, None, None)
        for probe_name in ("healthz", "curve"):
            values = result[probe_name]
            print(
                f"{name:9} {probe_name:8} n={len(values):4}  p50 {p(values, 50):7.1f} ms  "
                f"p99 {p(values, 99):7.1f} ms  max {max(values, default=0):7.1f} ms"
            )
        print(f"{name:9} replays  answers {dict(result['answers'])}")
        print(
            f"{name:9} memory   API process peak {result['api_mib']:.0f} MiB, pool processes "
            f"{', '.join(f'{m:.0f}' for m in result['pool_mib'])} MiB"
        )


if __name__ == "__main__":
    main()
