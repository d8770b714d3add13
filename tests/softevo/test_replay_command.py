"""`softevo replay` as a user runs it: a real GIF written and read back by Pillow (frame count
from fps x duration, the stated size, frames that differ because the robot moves), and every
failure one line on stderr (exit 1) or a usage error (exit 2). MP4 needs the ffmpeg program
(softevo does not ship it; .ci/run installs Debian's): without it the MP4 test skips on a laptop
and fails under CI=true."""

from __future__ import annotations

import itertools
import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from softevo.core.outputs import picture
from tests.softevo.inprocess import softevo

#: Rows at the top of a frame that hold the clock, which changes even on a still robot.
CLOCK_ROWS = 24


def frames(path: Path) -> list[np.ndarray]:
    with Image.open(path) as image:
        out = []
        for n in range(image.n_frames):
            image.seek(n)
            out.append(np.asarray(image.convert("RGB"), dtype=np.int16))
        return out


def test_gif_has_fps_times_duration_frames_of_the_size(examples: Path, tmp_path: Path) -> None:
    out = tmp_path / "crawl.gif"
    done = softevo(
        "replay",
        str(examples / "crawler_4x4x4.json"),
        "--out",
        str(out),
        "--fps",
        "5",
        "--duration",
        "1.6",
    )
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip() == f"{out}: gif, {out.stat().st_size} bytes"
    with Image.open(out) as image:
        assert image.format == "GIF" and image.n_frames == 8 and image.size == picture.SIZE
    shown = frames(out)
    for before, after in itertools.pairwise(shown):
        assert np.abs(after[CLOCK_ROWS:] - before[CLOCK_ROWS:]).sum() > 0  # the robot moves


def test_unknown_suffix_is_one_usage_line(examples: Path, tmp_path: Path) -> None:
    done = softevo("replay", str(examples / "crawler_4x4x4.json"), "--out", str(tmp_path / "a.avi"))
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and ".gif or .mp4" in done.stderr
    assert not (tmp_path / "a.avi").exists()


def test_bad_robot_file_is_one_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "softevo.robot/1"}')
    done = softevo("replay", str(bad), "--out", str(tmp_path / "a.gif"))
    assert done.returncode == 1
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("softevo replay: error:")
    assert str(bad) in done.stderr and not (tmp_path / "a.gif").exists()


@pytest.mark.parametrize(
    ("option", "value", "said"),
    [("--fps", "100", "--fps must be"), ("--duration", "999", "--duration must be")],
)
def test_out_of_range_fps_or_duration_is_one_line(
    examples: Path, tmp_path: Path, option: str, value: str, said: str
) -> None:
    done = softevo(
        "replay",
        str(examples / "crawler_4x4x4.json"),
        "--out",
        str(tmp_path / "a.gif"),
        option,
        value,
    )
    assert done.returncode == 2 and said in done.stderr and done.stderr.count("\n") == 1


def test_non_positive_fps_is_a_usage_error(examples: Path, tmp_path: Path) -> None:
    done = softevo(
        "replay",
        str(examples / "crawler_4x4x4.json"),
        "--out",
        str(tmp_path / "a.gif"),
        "--fps",
        "0",
    )
    assert done.returncode == 2 and "--fps" in done.stderr


def test_check_counts_frames_and_names_the_limit() -> None:
    assert picture.check(12, 3) == 36 and picture.check(0.5, 1) == 1
    with pytest.raises(picture.PictureError, match=f"at most {picture.MAX_PICTURE_SECONDS:g} s"):
        picture.check(10, picture.MAX_PICTURE_SECONDS * 2)
    with pytest.raises(picture.PictureError, match="fps"):
        picture.check(float("nan"), 1)
    with pytest.raises(picture.PictureError, match=f"between {picture.MIN_PICTURE_FPS:g}"):
        picture.check(1e-300, 1)


def test_thumbnail_is_a_png_of_the_stated_size(examples: Path) -> None:
    from io import BytesIO

    from softevo.core.robots.robot_file import load_robot

    data = picture.thumbnail_png(load_robot(examples / "crawler_4x4x4.json"))
    with Image.open(BytesIO(data)) as image:
        assert image.format == "PNG" and image.size == picture.THUMBNAIL_SIZE
        pixels = np.asarray(image.convert("RGB"))
    assert len(np.unique(pixels.reshape(-1, 3), axis=0)) > 10  # shaded faces, not a blank


def test_mp4_with_ffmpeg_has_the_frames_and_size_asked_for(examples: Path, tmp_path: Path) -> None:
    if not picture.ffmpeg_available() or shutil.which("ffprobe") is None:
        if os.environ.get("CI") == "true":
            pytest.fail("ffmpeg is needed under CI and is not installed (apt-get install ffmpeg)")
        pytest.skip("ffmpeg is not installed (apt-get install ffmpeg)")
    out = tmp_path / "crawl.mp4"
    done = softevo(
        "replay",
        str(examples / "crawler_4x4x4.json"),
        "--out",
        str(out),
        "--fps",
        "10",
        "--duration",
        "1.2",
    )
    assert done.returncode == 0, done.stderr
    assert out.read_bytes()[4:8] == b"ftyp"
    probe = subprocess.run(
        [
            "ffprobe",
            "-v",
            "error",
            "-count_frames",
            "-select_streams",
            "v:0",
            "-show_entries",
            "stream=nb_read_frames,width,height",
            "-of",
            "json",
            str(out),
        ],
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    )
    (stream,) = json.loads(probe.stdout)["streams"]
    assert int(stream["nb_read_frames"]) == 12
    assert (stream["width"], stream["height"]) == picture.SIZE


def test_mp4_without_ffmpeg_says_how_to_get_it(
    examples: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(picture, "ffmpeg_available", lambda: False)
    done = softevo("replay", str(examples / "crawler_4x4x4.json"), "--out", str(tmp_path / "a.mp4"))
    assert done.returncode == 1 and "install" in done.stderr and "ffmpeg" in done.stderr
    assert done.stderr.count("\n") == 1


def test_help_names_the_formats_and_ffmpeg() -> None:
    done = softevo("replay", "--help")
    assert done.returncode == 0 and "ffmpeg" in done.stdout and ".gif" in done.stdout
    assert "replay" in softevo("--help").stdout
