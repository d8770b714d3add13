"""Pictures of a run's best robot through the real app: the GIF (rendered in the replays' own
process) has fps x duration frames of the stated size, the thumbnail is a PNG of its size, both
with their media type and in the OpenAPI schema; out-of-range fps / duration are 422s that name
the limit, and an MP4 without ffmpeg is a 501 that says how to get it."""

from __future__ import annotations

import io
import os

import pytest
from fastapi.testclient import TestClient
from PIL import Image

from softevo.api import pictures
from softevo.core.limits import MIN_PICTURE_FPS, SERVICE_PICTURE_FPS, SERVICE_PICTURE_SECONDS
from softevo.core.outputs import picture
from tests.api.test_api import start, wait_for


@pytest.fixture
def finished(client: TestClient) -> int:
    run_id = start(client)
    wait_for(client, run_id, ("completed",))
    return run_id


def test_best_as_gif_and_thumbnail(client: TestClient, finished: int) -> None:
    response = client.get(f"/runs/{finished}/best/replay.gif", params={"fps": 4, "duration": 1.5})
    assert response.status_code == 200, response.text
    assert response.headers["content-type"] == "image/gif"
    with Image.open(io.BytesIO(response.content)) as image:
        assert image.n_frames == 6 and image.size == picture.SIZE
    again = client.get(f"/runs/{finished}/best/replay.gif", params={"fps": 4, "duration": 1.5})
    assert again.content == response.content  # remembered, not drawn anew

    thumbnail = client.get(f"/runs/{finished}/best/thumbnail.png")
    assert thumbnail.status_code == 200 and thumbnail.headers["content-type"] == "image/png"
    with Image.open(io.BytesIO(thumbnail.content)) as image:
        assert image.format == "PNG" and image.size == picture.THUMBNAIL_SIZE


@pytest.mark.parametrize(
    ("params", "limit"),
    [
        ({"fps": SERVICE_PICTURE_FPS + 1}, SERVICE_PICTURE_FPS),
        ({"fps": 0.1}, MIN_PICTURE_FPS),
        ({"duration": SERVICE_PICTURE_SECONDS * 2}, SERVICE_PICTURE_SECONDS),
    ],
)
def test_out_of_range_fps_or_duration_is_a_422(
    client: TestClient, params: dict[str, float], limit: float
) -> None:
    response = client.get("/runs/1/best/replay.gif", params=params)
    assert response.status_code == 422
    (error,) = response.json()["detail"]
    assert error["loc"] == ["query", next(iter(params))] and f"{limit:g}" in error["msg"]


def test_best_as_mp4_where_ffmpeg_is(client: TestClient, finished: int) -> None:
    if not picture.ffmpeg_available():
        if os.environ.get("CI") == "true":
            pytest.fail("ffmpeg is needed under CI and is not installed (apt-get install ffmpeg)")
        pytest.skip("ffmpeg is not installed (apt-get install ffmpeg)")
    response = client.get(f"/runs/{finished}/best/replay.mp4", params={"fps": 4, "duration": 1})
    assert response.status_code == 200, response.text
    assert response.headers["content-type"] == "video/mp4" and response.content[4:8] == b"ftyp"


def test_mp4_without_ffmpeg_is_a_501(
    client: TestClient, finished: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(picture, "ffmpeg_available", lambda: False)
    response = client.get(f"/runs/{finished}/best/replay.mp4")
    assert response.status_code == 501 and "ffmpeg" in response.json()["detail"]
    assert client.get(f"/runs/{finished}/best/replay.avi").status_code == 422


def test_no_best_yet_is_a_404(client: TestClient) -> None:
    assert client.get("/runs/999/best/thumbnail.png").status_code == 404
    assert client.get("/runs/999/best/replay.gif").status_code == 404


def test_the_schema_lists_the_pictures(client: TestClient) -> None:
    paths = client.get("/openapi.json").json()["paths"]
    gif = paths["/runs/{run_id}/best/replay.{format}"]["get"]
    assert set(gif["responses"]["200"]["content"]) == {"image/gif", "video/mp4"}
    assert "501" in gif["responses"]
    png = paths["/runs/{run_id}/best/thumbnail.png"]["get"]
    assert set(png["responses"]["200"]["content"]) == {"image/png"}


def test_the_thumbnail_cache_is_bounded() -> None:
    assert pictures.CACHED_THUMBNAILS >= 100 and pictures.CACHED_MOVIES >= 1
