"""docker-compose.yml cannot be run here (no Docker engine), so check what it says: every service
runs a `softevo` command that exists, mounts declared volumes, and builds from the Dockerfile."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from softevo.cli import main

ROOT = Path(__file__).resolve().parent.parent


def load_compose() -> dict:
    return yaml.safe_load((ROOT / "docker-compose.yml").read_text())


def test_services_run_existing_softevo_commands() -> None:
    compose = load_compose()
    assert compose["services"], "no services"
    for name, service in compose["services"].items():
        argv = [*service.get("entrypoint", []), *service.get("command", [])]
        assert argv[0] == "softevo", f"{name} does not run softevo: {argv}"
        with pytest.raises(SystemExit) as exited:  # `softevo COMMAND --help` exits 0 if it exists
            main([argv[1], "--help"])
        assert exited.value.code == 0, f"{name} runs unknown command {argv[1]!r}"
        for arg in argv[2:]:
            if arg.endswith(".json"):
                assert (ROOT / arg).is_file(), f"{name} refers to missing file {arg}"


def test_volumes_are_declared_and_image_builds_from_dockerfile() -> None:
    compose = load_compose()
    declared = set(compose.get("volumes") or {})
    for name, service in compose["services"].items():
        for mount in service.get("volumes", []):
            source = mount.split(":")[0]
            if not source.startswith((".", "/")):
                assert source in declared, f"{name} mounts undeclared volume {source}"
        if "build" in service:
            assert (ROOT / "Dockerfile").is_file()


def test_dockerfile_runs_as_non_root_and_copies_every_package() -> None:
    dockerfile = (ROOT / "Dockerfile").read_text()
    users = [line.split()[1] for line in dockerfile.splitlines() if line.startswith("USER ")]
    assert users and users[-1] not in {"root", "0"}
    for package in ("core", "api", "worker", "softevo", "migrations", "examples"):
        assert f"COPY {package} " in dockerfile, f"Dockerfile does not copy {package}/"


def test_only_the_api_publishes_a_port_and_it_is_the_one_it_serves() -> None:
    services = load_compose()["services"]
    published = {name for name, service in services.items() if service.get("ports")}
    assert published == {"api"}
    api = services["api"]
    assert api["ports"] == ["8000:8000"]
    assert api["command"][api["command"].index("--port") + 1] == "8000"
    assert "--host" in api["command"] and "0.0.0.0" in api["command"]
    assert "/healthz" in " ".join(api["healthcheck"]["test"])
    assert api["environment"]["SOFTEVO_DATABASE_URL"].startswith("sqlite:////data/")
    assert any(mount.endswith(":/data") for mount in api["volumes"])
