"""docker-compose.yml cannot be run here (no Docker engine), so check what it says: the api, RQ
workers, Redis and PostgreSQL, each softevo service running a `softevo` command that exists, only
the api reachable from outside, healthchecks and restart policies, persistence on declared
volumes, secrets only from variables that `.env.example` documents, and a non-root image."""

from __future__ import annotations

import re
import shutil
import subprocess
import tomllib
from pathlib import Path
from typing import Any

import pytest
import yaml

from softevo.cli import main

ROOT = Path(__file__).resolve().parent.parent
SOFTEVO_IMAGE = "softevo:latest"
LONG_RUNNING = ("api", "worker", "redis", "postgres")
VARIABLE = re.compile(r"^\$\{(\w+)(:?[-?][^}]*)?\}$")  # the whole value is one ${NAME...}


def load_compose() -> dict:
    return yaml.safe_load((ROOT / "docker-compose.yml").read_text())


def softevo_services(compose: dict) -> dict[str, dict]:
    return {
        name: service
        for name, service in compose["services"].items()
        if "build" in service or service.get("image") == SOFTEVO_IMAGE
    }


def strings(node: Any) -> list[str]:
    """Every string (keys included) in a parsed YAML tree."""
    if isinstance(node, str):
        return [node]
    if isinstance(node, dict):
        return [text for key, value in node.items() for text in strings(key) + strings(value)]
    if isinstance(node, list):
        return [text for item in node for text in strings(item)]
    return []


def variables_used(compose: dict) -> set[str]:
    """Names compose interpolates (`$$` is a literal dollar left to the container)."""
    names: set[str] = set()
    for text in strings(compose):
        text = text.replace("$$", "")
        names.update(re.findall(r"\$\{(\w+)", text))
        names.update(re.findall(r"\$(\w+)", text))
    return names


def url_password(url: str) -> str:
    match = re.match(r"^\w+://[^:/@]*:(.*)@[^@]+$", url)
    assert match, f"{url} has no password"
    return match.group(1)


def healthy(service: dict, dependency: str) -> bool:
    depends = service.get("depends_on") or {}
    return isinstance(depends, dict) and depends.get(dependency, {}).get("condition") == (
        "service_healthy"
    )


def test_the_stack_is_api_workers_redis_postgres_and_the_simulate_tool() -> None:
    services = load_compose()["services"]
    assert set(services) == {"api", "worker", "redis", "postgres", "simulate"}
    assert set(softevo_services(load_compose())) == {"api", "worker", "simulate"}
    assert services["simulate"]["profiles"] == ["tools"]  # only when named
    for name in LONG_RUNNING:
        assert "profiles" not in services[name], f"`docker compose up` must start {name}"


@pytest.mark.parametrize("name", sorted(softevo_services(load_compose())))
def test_services_run_existing_softevo_commands(name: str) -> None:
    service = load_compose()["services"][name]
    assert service.get("image") == SOFTEVO_IMAGE
    argv = [*service.get("entrypoint", []), *service.get("command", [])]
    assert argv[0] == "softevo", f"{name} does not run softevo: {argv}"
    with pytest.raises(SystemExit) as exited:  # `softevo COMMAND --help` exits 0 if it exists
        main([argv[1], "--help"])
    assert exited.value.code == 0, f"{name} runs unknown command {argv[1]!r}"
    for arg in argv[2:]:
        if arg.endswith(".json"):
            assert (ROOT / arg).is_file(), f"{name} refers to missing file {arg}"


def test_one_image_is_built_and_the_other_services_run_it() -> None:
    """`docker compose build` builds once: only the api has `build`; the worker and simulate
    run the image it tags and never try to pull it from a registry (it is not on one)."""
    services = softevo_services(load_compose())
    builders = {name for name, service in services.items() if "build" in service}
    assert builders == {"api"} and services["api"]["build"] == "."
    for name in set(services) - builders:
        assert services[name]["image"] == services["api"]["image"] == SOFTEVO_IMAGE
        assert services[name]["pull_policy"] == "never", name


def test_volumes_are_declared_and_image_builds_from_dockerfile() -> None:
    compose = load_compose()
    declared = set(compose.get("volumes") or {})
    used = set()
    for name, service in compose["services"].items():
        for mount in service.get("volumes", []):
            source = mount.split(":")[0]
            if not source.startswith((".", "/")):
                assert source in declared, f"{name} mounts undeclared volume {source}"
                used.add(source)
        if "build" in service:
            assert (ROOT / "Dockerfile").is_file()
    assert used == declared, f"declared but unused: {declared - used}"


def test_dockerfile_runs_as_non_root_and_copies_every_package() -> None:
    dockerfile = (ROOT / "Dockerfile").read_text()
    users = [line.split()[1] for line in dockerfile.splitlines() if line.startswith("USER ")]
    assert users and users[-1] not in {"root", "0"} and not users[-1].startswith(("root:", "0:"))
    assert re.search(r"useradd .*--uid 10001 softevo", dockerfile)
    # Through the lock CI uses (the same versions, hashes checked), then the package on top of it
    lock = re.search(r"^RUN pip install -r requirements/runtime\.txt\s*$", dockerfile, re.MULTILINE)
    assert lock and "COPY requirements/runtime.txt " in dockerfile, "not through the lock"
    on_lock = re.search(r"^RUN pip install --no-deps --no-build-isolation \.\s", dockerfile, re.M)
    assert on_lock and on_lock.start() > lock.start(), "the package is not installed on the lock"
    # every folder pyproject.toml installs (a folder left out fails `pip install .` in the image,
    # as docs/ did once `softevo docs` shipped the guides), and the example robots
    folders = set(
        tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"][
            "package-dir"
        ].values()
    ) | {"examples"}
    for folder in sorted(folders):
        assert re.search(rf"^COPY {folder}[ /]", dockerfile, re.M), f"no COPY of {folder}/"
    # The numba cache volume is mounted here: it must exist, owned by the user, in the image.
    assert "/home/softevo/.cache/numba" in dockerfile
    # ... and hold the compiled kernels: compiled at build time, as that user, after the install
    compile_step = (
        r"^RUN python -P -c .*softevo\.core\.physics\.evaluation import warm_up; warm_up\(\)"
    )
    warm = re.search(compile_step, dockerfile, re.M)
    user = dockerfile.rindex("\nUSER ")
    assert warm and warm.start() > user > on_lock.start(), "kernels not compiled into the image"
    assert re.search(r"^ENV [^#]*NUMBA_CACHE_DIR=/home/softevo/\.cache/numba", dockerfile, re.M)


def test_only_the_api_publishes_a_port_and_it_is_the_one_it_serves() -> None:
    services = load_compose()["services"]
    published = {name for name, service in services.items() if service.get("ports")}
    assert published == {"api"}
    assert all("expose" not in service for service in services.values())
    api = services["api"]
    assert api["ports"] == ["8000:8000"]
    assert api["command"][:3] == ["softevo", "serve", "--migrate"]
    assert api["command"][api["command"].index("--port") + 1] == "8000"
    assert "--host" in api["command"] and "0.0.0.0" in api["command"]
    assert "/healthz" in " ".join(api["healthcheck"]["test"])
    assert api["healthcheck"]["test"][:2] == ["CMD", "python"]  # no curl in the slim image


def test_api_uses_postgres_and_redis_and_waits_until_they_are_healthy() -> None:
    services = load_compose()["services"]
    api = services["api"]
    database = api["environment"]["SOFTEVO_DATABASE_URL"]
    assert database.startswith("postgresql://softevo:")
    assert database.endswith("@postgres:5432/softevo")
    assert api["environment"]["SOFTEVO_REDIS_URL"].startswith("redis://:")
    assert api["environment"]["SOFTEVO_REDIS_URL"].endswith("@redis:6379/0")
    assert api["environment"]["SOFTEVO_API_TOKEN"] == "${SOFTEVO_API_TOKEN:-}"
    assert healthy(api, "postgres") and healthy(api, "redis")


def test_two_workers_share_the_image_and_reach_redis() -> None:
    services = load_compose()["services"]
    worker = services["worker"]
    # no fork per job by default (`softevo.worker.watchdog` keeps the hard limit), one variable away
    assert worker["command"] == [
        "softevo",
        "worker",
        "--worker-class",
        "${SOFTEVO_WORKER_CLASS:-simple}",
    ]
    assert worker["deploy"]["replicas"] == 2
    api_redis = services["api"]["environment"]["SOFTEVO_REDIS_URL"]
    assert worker["environment"]["SOFTEVO_REDIS_URL"] == api_redis
    assert healthy(worker, "redis")
    assert any(mount.endswith(":/home/softevo/.cache/numba") for mount in worker["volumes"])
    assert "container_name" not in worker  # would forbid more than one replica


def test_redis_persists_requires_a_password_and_runs_unprivileged() -> None:
    redis = load_compose()["services"]["redis"]
    assert redis["image"].startswith("redis:7")
    command = redis["command"]
    # First argument redis-server: the official entrypoint drops from root to the `redis` user.
    assert command[0] == "redis-server" and redis.get("user") in (None, "redis")
    assert command[command.index("--appendonly") + 1] == "yes"
    password = command[command.index("--requirepass") + 1]
    assert VARIABLE.match(password) and VARIABLE.match(password).group(1) == "REDIS_PASSWORD"
    assert any(mount.endswith(":/data") for mount in redis["volumes"])
    test = " ".join(redis["healthcheck"]["test"])
    assert "redis-cli" in test and "ping" in test and '"$$REDIS_PASSWORD"' in test
    assert VARIABLE.match(redis["environment"]["REDIS_PASSWORD"])  # what the healthcheck reads
    assert not redis.get("ports")


def test_postgres_persists_and_reports_readiness() -> None:
    postgres = load_compose()["services"]["postgres"]
    assert re.match(r"postgres:1[56]-alpine$", postgres["image"])
    env = postgres["environment"]
    assert env["POSTGRES_USER"] == "softevo" and env["POSTGRES_DB"] == "softevo"
    assert VARIABLE.match(env["POSTGRES_PASSWORD"]).group(1) == "POSTGRES_PASSWORD"
    assert any(mount.endswith(":/var/lib/postgresql/data") for mount in postgres["volumes"])
    test = postgres["healthcheck"]["test"]
    assert "pg_isready" in test and "softevo" in test
    assert not postgres.get("ports")


def test_passwords_come_from_variables_never_literals() -> None:
    services = load_compose()["services"]
    for name in ("api", "worker"):
        for key, value in services[name]["environment"].items():
            if key.endswith("_URL"):
                password = url_password(value)
                assert VARIABLE.match(password), f"{name} {key} has a literal password"
    assert VARIABLE.match(url_password(services["api"]["environment"]["SOFTEVO_DATABASE_URL"]))
    for name, service in services.items():
        for key, value in (service.get("environment") or {}).items():
            if any(word in key for word in ("PASSWORD", "TOKEN", "SECRET")):
                assert VARIABLE.match(str(value)), f"{name} {key} is a literal: {value!r}"
    # The required ones fail loudly when unset instead of starting with an empty password.
    for name in ("POSTGRES_PASSWORD", "REDIS_PASSWORD"):
        for text in strings(services):
            for found in re.findall(r"\$\{" + name + r"([^}]*)\}", text.replace("$$", "")):
                assert found.startswith(":?"), f"${{{name}}} must be required (:?)"


def test_long_running_services_restart_and_have_healthchecks() -> None:
    services = load_compose()["services"]
    for name in LONG_RUNNING:
        assert services[name].get("restart") in {"unless-stopped", "always"}, name
    for name in ("api", "redis", "postgres"):
        assert services[name]["healthcheck"]["test"], f"{name} has no healthcheck"


def test_every_variable_is_documented_in_env_example() -> None:
    documented = {
        line.split("=", 1)[0].strip()
        for line in (ROOT / ".env.example").read_text().splitlines()
        if "=" in line and not line.lstrip().startswith("#")
    }
    used = variables_used(load_compose())
    assert used == {
        "POSTGRES_PASSWORD",
        "REDIS_PASSWORD",
        "SOFTEVO_API_TOKEN",
        "SOFTEVO_PROTECT_READS",
        "SOFTEVO_WORKER_CLASS",
    }
    assert used <= documented, f"missing from .env.example: {used - documented}"


def ignored_by_git(path: str) -> bool:
    if shutil.which("git") and (ROOT / ".git").exists():
        done = subprocess.run(
            ["git", "check-ignore", "-q", "--no-index", path], cwd=ROOT, check=False
        )
        assert done.returncode in (0, 1), "git check-ignore failed"
        return done.returncode == 0
    patterns = (ROOT / ".gitignore").read_text().splitlines()
    return path in {pattern.strip().lstrip("/") for pattern in patterns}


def test_env_file_is_ignored_by_git_and_docker() -> None:
    assert ignored_by_git(".env")
    assert not ignored_by_git(".env.example")
    dockerignore = (ROOT / ".dockerignore").read_text().splitlines()
    assert ".env" in dockerignore and ".git" in dockerignore
