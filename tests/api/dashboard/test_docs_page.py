"""`/docs` works offline: Swagger UI from the package's vendored files, never a CDN (FastAPI's
default page is blank on a machine without internet)."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from softevo.api.app import create_app
from softevo.api.settings import Settings
from softevo.core.physics.evaluation import SerialEvaluator

VENDOR = Path(__file__).resolve().parents[3] / "api" / "dashboard" / "static" / "vendor"


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    database = tmp_path_factory.mktemp("docs") / "softevo.db"
    app = create_app(Settings(database_url=f"sqlite:///{database}"), lambda _s: SerialEvaluator())
    with TestClient(app) as client:
        yield client


def test_docs_loads_nothing_from_the_network(client: TestClient) -> None:
    page = client.get("/docs")
    assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
    scripts = re.findall(r"<script[^>]*\bsrc=['\"]([^'\"]+)", page.text)
    links = re.findall(r"<link[^>]*\bhref=['\"]([^'\"]+)", page.text)
    assert scripts and links, page.text
    assert not [url for url in scripts + links if re.match(r"(https?:)?//", url)]
    assert "openapi.json" in page.text
    kinds = {".js": "javascript", ".css": "text/css", ".png": "image/png"}
    for url in scripts + links:
        response = client.get(url)
        assert response.status_code == 200, url
        assert kinds[Path(url).suffix] in response.headers["content-type"], url
        assert len(response.content) > 500, url  # the real file, not a stub
    bundle = client.get(scripts[0]).text
    assert "SwaggerUIBundle" in bundle


def test_redoc_is_off_and_the_schema_is_served(client: TestClient) -> None:
    """ReDoc would load its script from a CDN: it is not served at all."""
    assert client.get("/redoc").status_code == 404
    schema = client.get("/openapi.json").json()
    assert "/runs" in schema["paths"] and "/docs" not in schema["paths"]


def test_swagger_ui_carries_its_licence() -> None:
    assert "Apache License" in (VENDOR / "swagger-ui" / "LICENSE").read_text()
    assert "SmartBear" in (VENDOR / "swagger-ui" / "NOTICE").read_text()
    sums = {line.split()[1] for line in (VENDOR / "SHA256SUMS").read_text().splitlines()}
    assert {"./swagger-ui/swagger-ui-bundle.js", "./swagger-ui/swagger-ui.css"} <= sums
