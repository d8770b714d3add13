"""`softevo.client` against a real `softevo serve` (SQLite, a token set): runs and sweeps end to
end, the API's errors as exceptions with its words, and an import that loads no engine."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from softevo.client import FINAL, APIError, Client, UnreachableError
from softevo.core.status import FINAL as STATUS_FINAL
from softevo.local_service import LocalService, free_port, service_env, start_service

TOKEN = "s3cret"
#: Small enough for seconds on one core: 4 robots x 2 generations of 1 simulated second.
TINY = {"preset": "quick", "population": 4, "generations": 2, "shape": [2, 2, 2]}
TINY_SIM = {"duration": 1.0, "settle_time": 0.2}


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalService]:
    folder = tmp_path_factory.mktemp("client")
    env = service_env(
        database_url=f"sqlite:///{folder / 'softevo.db'}", api_token=TOKEN, workers="1"
    )
    with start_service(env, folder / "service.log", "--log-level", "warning", timeout=120) as s:
        yield s


@pytest.fixture
def client(service: LocalService) -> Iterator[Client]:
    with Client(service.url, token=TOKEN) as client:
        yield client


def test_a_run_from_start_to_best_robot(client: Client, capsys: pytest.CaptureFixture[str]) -> None:
    run = client.run(**TINY, seed=3, sim=TINY_SIM)
    assert run.data is not None and run.data["status"] in {"queued", "running"}
    final = run.wait(progress=True, poll=0.2, timeout=120)
    assert final["status"] == "completed" and run.status()["status"] == "completed"
    assert f"run {run.id}: generation 2/2" in capsys.readouterr().err  # the progress line
    curve = run.curve()
    assert [row["generation"] for row in curve] == [0, 1]
    assert curve[-1]["best_so_far"] == pytest.approx(final["progress"]["best_fitness"])
    individuals = run.individuals()
    assert len(individuals) == 4 * 2 and {i["generation"] for i in individuals} == {0, 1}
    assert len(run.individuals(generation=1)) == 4
    best = run.best()
    assert best["format"] == "softevo.robot/1" and best["shape"] == [2, 2, 2]
    replay = run.replay(fps=10)
    assert replay["run_id"] == run.id and replay["fitness"] == pytest.approx(
        final["progress"]["best_fitness"]
    )
    with pytest.raises(APIError) as refused:  # a finished run cannot be cancelled
        run.cancel()
    assert refused.value.status == 409 and str(run.id) in refused.value.message


def test_a_map_elites_runs_archive(client: Client) -> None:
    qd = {"algorithm": "map-elites", "descriptors": ["voxels", "actuated"], "bins": [3, 3]}
    run = client.run(**TINY, **qd, seed=2, sim=TINY_SIM)
    assert run.wait(timeout=120)["status"] == "completed"
    archive = run.archive(robots=True)
    assert archive["coverage"] == len(archive["cells"]) / 9 and archive["cells"]
    assert all(cell["robot"]["format"] == "softevo.robot/1" for cell in archive["cells"])
    assert run.curve()[-1]["qd_score"] == archive["qd_score"]
    plain = client.run(**TINY, seed=2, sim=TINY_SIM)
    plain.wait(timeout=120)
    with pytest.raises(APIError) as refused:
        plain.archive()
    assert refused.value.status == 404 and "without descriptors" in refused.value.message


def test_an_nsga2_runs_front(client: Client) -> None:
    run = client.run(
        **TINY, algorithm="nsga2", objectives=["speed", "-cost_of_transport"], seed=2, sim=TINY_SIM
    )
    assert run.wait(timeout=120)["status"] == "completed"
    front = run.front(robots=True)
    assert front["points"] and front["objectives"][1]["goal"] == "min"
    assert all(point["robot"]["format"] == "softevo.robot/1" for point in front["points"])
    assert all(point["measures"]["cost_of_transport"] is not None for point in front["points"])


def test_cancel_and_a_wait_that_times_out(client: Client) -> None:
    run = client.run(**{**TINY, "generations": 500}, sim=TINY_SIM)
    with pytest.raises(TimeoutError, match=f"run {run.id}"):
        run.wait(progress=False, poll=0.1, timeout=0.3)
    assert run.cancel()["status"] == "cancelled"
    assert run.wait(progress=False)["status"] == "cancelled"  # final: returns at once


def test_a_sweep_waits_for_every_run(client: Client) -> None:
    base = {k: v for k, v in TINY.items() if k != "shape"}
    sweep = client.sweep(**base, shapes=[[2, 2, 2]], seeds=[1, 2], sim=TINY_SIM)
    done = sweep.wait(progress=False, poll=0.2, timeout=180)
    assert done["status"] == "completed"
    runs = sweep.runs()
    assert len(runs) == 2 and {r.status()["seed"] for r in runs} == {1, 2}
    curves = sweep.curves()
    assert set(curves) == {r.id for r in runs} and all(len(c) == 2 for c in curves.values())
    assert client.get_sweep(sweep.id).status()["boxes"][0]["completed"] == 2


def test_errors_carry_the_apis_message(service: LocalService, client: Client) -> None:
    with pytest.raises(APIError) as too_big:
        client.run(preset="quick", population=2000)
    assert too_big.value.status == 422
    assert too_big.value.message.startswith("population: ") and "SOFTEVO_MAX_POPULATION" in str(
        too_big.value
    )
    with pytest.raises(APIError) as unknown:
        client.run(preset="quick", colour="red")
    assert unknown.value.status == 422 and unknown.value.message.startswith("colour: ")
    with pytest.raises(APIError) as missing:
        client.get_run(2**31 - 1).status()
    assert missing.value.status == 404 and missing.value.message == f"run {2**31 - 1} not found"
    with Client(service.url) as anonymous:  # reads are open, a state change needs the token
        assert anonymous.health()["status"] == "ok"
        with pytest.raises(APIError) as no_token:
            anonymous.run(**TINY)
        assert no_token.value.status == 401 and "Authorization: Bearer" in no_token.value.message
    with Client(service.url, token="wrong") as wrong, pytest.raises(APIError) as bad:
        wrong.run(**TINY)
    assert bad.value.status == 403 and bad.value.message == "wrong bearer token"


def test_a_service_that_is_not_there_is_unreachable() -> None:
    with Client(f"http://127.0.0.1:{free_port()}", timeout=2) as nobody:
        with pytest.raises(UnreachableError):
            nobody.run(**TINY)
        with pytest.raises(UnreachableError):
            nobody.health()


def test_runs_lists_every_run_across_pages(client: Client) -> None:
    listed = list(client.runs(page=1))
    assert len(listed) == len({r["id"] for r in listed}) >= 1
    assert [r["id"] for r in listed] == sorted((r["id"] for r in listed), reverse=True)
    assert {p["name"] for p in client.presets()} >= {"quick", "paper-voxel"}


def test_the_final_statuses_are_the_engines() -> None:
    assert {str(s) for s in STATUS_FINAL} == FINAL


def test_importing_the_client_loads_no_engine() -> None:
    """A notebook that only drives a service never pays for numba (or needs it)."""
    check = (
        "import sys, softevo.client; "
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('numba', 'numpy') "
        "or m.startswith(('softevo.core', 'softevo.api'))))"
    )
    done = subprocess.run(
        [sys.executable, "-P", "-c", check],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=Path(__file__).parent,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
