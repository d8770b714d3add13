"""`softevo plot RUN_ID` reads a run from a live service (with its token) and draws real PNGs."""

from __future__ import annotations

import os
import struct
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from tests.api.dashboard.live import serve, wait

pytestmark = pytest.mark.slow
KINDS = ("curve", "population", "diversity")
RUN = {
    "preset": "quick",
    "seed": 4,
    "population": 6,
    "generations": 3,
    "sim": {"duration": 1.0, "settle_time": 0.2},
}


def png_size(path: Path) -> tuple[int, int]:
    """(width, height) from the PNG header; fails unless the file starts as a PNG does."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR", path
    return struct.unpack(">II", data[16:24])


def test_plot_a_run_of_the_service(tmp_path: Path) -> None:
    with serve(tmp_path, token="tok") as server:
        headers = {"Authorization": "Bearer tok"}
        run_id = server.post("/runs", json=RUN, headers=headers).json()["id"]
        wait(
            lambda: server.get(f"/runs/{run_id}").json()["status"] == "completed",
            60,
            "run done",
        )
        env = {**os.environ, "SOFTEVO_API_TOKEN": "tok"}

        def plot(*args: str) -> subprocess.CompletedProcess[str]:
            return subprocess.run(
                [
                    sys.executable,
                    "-P",
                    "-m",
                    "softevo.cli",
                    "plot",
                    *args,
                    "--url",
                    str(server.base_url),
                ],
                capture_output=True,
                text=True,
                env=env,
                timeout=120,
            )

        stacked = tmp_path / "all.png"
        done = plot(str(run_id), "--out", str(stacked))
        assert done.returncode == 0, done.stderr
        width, height = png_size(stacked)
        assert height > 1.4 * width  # three panels, stacked (6 x 9 in)
        assert stacked.stat().st_size > 30_000
        one = tmp_path / "population.png"
        assert plot(str(run_id), "--out", str(one), "--kind", "population").returncode == 0
        width, height = png_size(one)
        assert width > height and one.stat().st_size > 10_000
        # the service's own PNGs, asked for all at once (pyplot is not thread-safe: serialised)
        paths = [f"/runs/{run_id}/figures/{kind}.png" for kind in KINDS * 3]
        with ThreadPoolExecutor(len(paths)) as pool:
            answers = list(pool.map(server.get, paths))
        for answer in answers:
            assert answer.status_code == 200 and answer.headers["content-type"] == "image/png"
            assert answer.content[:4] == b"\x89PNG" and len(answer.content) > 10_000
        assert answers[0].content == answers[3].content  # the same figure, byte for byte
        missing = plot("9999", "--out", str(tmp_path / "none.png"))
        assert missing.returncode == 1 and "run 9999 not found" in missing.stderr
        assert not (tmp_path / "none.png").exists()
