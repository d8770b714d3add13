"""A third-party strategy, installed as a package of its own through the entry-point group
`softevo.strategies`, runs through the CLI, the library and the service (on RQ too) to the same
curve. Its code and its registration are the text of docs/evolution.md, "A strategy of your own".
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from softevo import library
from softevo.api.app import create_app
from softevo.api.db import Database
from softevo.api.settings import Settings
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search.registry import GROUP, strategies
from tests.api.finished import finished
from tests.softevo.inprocess import softevo

DOC = Path(__file__).resolve().parents[2] / "docs" / "evolution.md"
NAME = "elite-mutants"
RUN = {
    "preset": "quick",
    "algorithm": NAME,
    "options": {"keep": 3},
    "population": 6,
    "generations": 3,
    "seed": 4,
    "sim": {"duration": 1.0},
}


def section(heading: str, language: str) -> str:
    """The `language` block of the docs' `## heading` section."""
    body = DOC.read_text().split(f"## {heading}\n", 1)[1].split("\n## ", 1)[0]
    found = re.search(rf"^```{language}\n(.*?)^```$", body, re.MULTILINE | re.DOTALL)
    assert found, f"no {language} block under {heading}"
    return found.group(1)


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The docs' package installed the way pip installs one: its module and a dist-info folder
    with its entry points, on the path of this process and of the processes it starts."""
    root = tmp_path_factory.mktemp("site")
    (root / "elite_mutants.py").write_text(section("A strategy of your own", "python"))
    points = tomllib.loads(section("A strategy of your own", "toml"))["project"]
    dist = root / "elite_mutants-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: elite-mutants\nVersion: 0.1\n")
    lines = [f"{name} = {target}" for name, target in points["entry-points"][GROUP].items()]
    (dist / "entry_points.txt").write_text(f"[{GROUP}]\n" + "\n".join(lines) + "\n")
    sys.path.insert(0, str(root))
    strategies.cache_clear()
    yield root
    sys.path.remove(str(root))
    sys.modules.pop("elite_mutants", None)
    strategies.cache_clear()


def environment(site: Path) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), *sys.path])}


def test_it_is_listed_by_softevo_algorithms_in_a_new_process(site: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "softevo.cli", "algorithms", "--json"],
        capture_output=True,
        text=True,
        env=environment(site),
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    listed = {entry["name"]: entry for entry in json.loads(done.stdout)}
    assert {"ga", "random", "hillclimb", "map-elites", NAME} <= set(listed)
    assert listed[NAME]["options"]["properties"]["keep"]["default"] == 2
    assert [item["name"] for item in listed[NAME]["uses"]][:2] == ["population", "generations"]


def test_cli_library_and_service_give_one_curve(site: Path, tmp_path: Path) -> None:
    out = tmp_path / "run"
    done = softevo(
        "run",
        "--preset",
        "quick",
        "--algorithm",
        NAME,
        "--options",
        '{"keep": 3}',
        "--population",
        "6",
        "--generations",
        "3",
        "--seed",
        "4",
        "--duration",
        "1",
        "--workers",
        "1",
        "--out",
        str(out),
        "--json",
    )
    assert done.returncode == 0, done.stderr
    cli = json.loads(done.stdout)["generations"]
    result = library.evolve(RUN, workers=1)
    assert result.curve == cli and len(cli) == 3
    assert json.loads((out / "config.json").read_text())["options"] == {"keep": 3}
    url = f"sqlite:///{tmp_path / 'softevo.db'}"
    Database(url).upgrade()
    settings = Settings(database_url=url, poll_seconds=0.05, lease_seconds=5.0)
    with TestClient(create_app(settings, lambda _settings: SerialEvaluator())) as client:
        listed = [entry["name"] for entry in client.get("/algorithms").json()]
        created = client.post("/runs", json=RUN)
        assert created.status_code == 201, created.text
        assert finished(client, created.json()["id"])["status"] == "completed"
        served = client.get(f"/runs/{created.json()['id']}/curve").json()["generations"]
        refused = client.post("/runs", json={**RUN, "options": {"keep": 6}})
        wrong = client.post("/runs", json={**RUN, "options": {"keep": "3"}})
    assert NAME in listed and served == cli
    assert refused.status_code == 422 and "options.keep" in refused.text
    assert wrong.status_code == 422 and "options.keep" in wrong.text


API_ON_RQ = """
import json, sys, time
from fastapi.testclient import TestClient
from softevo.api.app import create_app
from softevo.api.settings import Settings
database, redis, run = "sqlite:///" + sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
settings = Settings(database_url=database, redis_url=redis, poll_seconds=0.05)
with TestClient(create_app(settings)) as client:
    created = client.post("/runs", json=run).json()
    deadline = time.monotonic() + 90
    while client.get(f"/runs/{created['id']}").json()["status"] != "completed":
        assert time.monotonic() < deadline
        time.sleep(0.05)
    curve = client.get(f"/runs/{created['id']}/curve").json()["generations"]
    items = client.get(f"/runs/{created['id']}/individuals").json()["items"]
print(json.dumps({"curve": curve, "workers": sorted({i["worker"] for i in items if i["worker"]})}))
"""


@pytest.mark.redis
def test_the_service_on_rq_runs_it_to_the_same_curve(
    site: Path, redis_server, workers, tmp_path: Path
) -> None:
    """The API process has the package; the worker only simulates and does not need it."""
    workers.start("plain")
    workers.wait_ready("plain")
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            API_ON_RQ,
            str(tmp_path / "api.db"),
            redis_server.url,
            json.dumps(RUN),
        ],
        capture_output=True,
        text=True,
        env=environment(site),
        timeout=150,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    served = json.loads(done.stdout.strip().splitlines()[-1])
    assert served["workers"] == ["plain"]
    assert served["curve"] == library.evolve(RUN, workers=1).curve
