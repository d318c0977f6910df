"""The reader on damaged copies of a campaign egogen-run made (EGOGEN_CAMPAIGN): each bad file
gives egogen.FormatError (a missing frame file FileNotFoundError) naming the file and the key or
field. The campaign itself is never touched: every test damages a copy in tmp_path."""

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

import egogen

CAMPAIGN = Path(os.environ.get("EGOGEN_CAMPAIGN", ""))
pytestmark = pytest.mark.skipif(not (CAMPAIGN / "campaign.json").is_file(), reason="EGOGEN_CAMPAIGN not set")


@pytest.fixture
def campaign(tmp_path) -> Path:
    """A copy of the campaign."""
    copy = tmp_path / "campaign"
    shutil.copytree(CAMPAIGN, copy, symlinks=True)
    return copy


def first_camera(campaign: Path) -> Path:
    """The first finished take's first camera folder (annotations.json and its frame files)."""
    take = egogen.open(campaign).take_ids[0]
    cameras = sorted((campaign / "takes" / take / "cameras").iterdir())
    return cameras[0]


def rewrite_json(path: Path, change):
    doc = json.loads(path.read_text())
    change(doc)
    path.write_text(json.dumps(doc))


def test_a_truncated_campaign_json(campaign):
    state = campaign / "campaign.json"
    text = state.read_bytes()
    state.write_bytes(text[: len(text) // 2])
    with pytest.raises(egogen.FormatError, match="not valid JSON") as e:
        egogen.open(campaign)
    assert str(state) in str(e.value) and "line " in str(e.value)
    assert isinstance(e.value.__cause__, json.JSONDecodeError)
    assert isinstance(e.value, ValueError)


def test_a_campaign_json_without_takes_or_a_take_status(campaign):
    state = campaign / "campaign.json"
    rewrite_json(state, lambda d: d.pop("takes"))
    with pytest.raises(egogen.FormatError) as e:
        egogen.open(campaign)
    assert str(state) in str(e.value) and "key takes: missing (expected a list of takes)" in str(e.value)

    shutil.copy(CAMPAIGN / "campaign.json", state)
    rewrite_json(state, lambda d: d["takes"][1].pop("status"))
    with pytest.raises(egogen.FormatError) as e:
        egogen.open(campaign)
    assert str(state) in str(e.value) and "key takes[1].status: missing" in str(e.value)


def test_an_annotations_file_that_is_not_json(campaign):
    cam = first_camera(campaign)
    p = cam / "annotations.json"
    p.write_bytes(b"\x89PNG not json at all")
    c = egogen.open(campaign)  # the campaign opens: a take's files are read when asked for
    with pytest.raises(egogen.FormatError, match="not valid JSON") as e:
        next(c.frames())
    assert str(p) in str(e.value)


def test_a_frame_without_T_world_cam_or_with_a_3x4_one(campaign):
    cam = first_camera(campaign)
    p = cam / "annotations.json"
    rewrite_json(p, lambda d: d["frames"][3].pop("T_world_cam"))
    frames = egogen.open(campaign).frames()
    for _ in range(3):  # the frames before it are built; the damaged one fails when built
        next(frames)
    with pytest.raises(egogen.FormatError) as e:
        next(frames)
    assert str(e.value) == f"{p}: key frames[3].T_world_cam: missing (expected a 4x4 matrix)"

    shutil.copy(first_camera(CAMPAIGN) / "annotations.json", p)
    rewrite_json(p, lambda d: d["frames"][2]["T_world_cam"].pop())
    with pytest.raises(egogen.FormatError) as e:
        list(egogen.open(campaign).frames())
    assert str(p) in str(e.value) and "key frames[2].T_world_cam" in str(e.value) and "4x4" in str(e.value)


def a_frame(campaign: Path, i: int = 1) -> egogen.Frame:
    frames = list(egogen.open(campaign).frames())
    assert frames[i].read()  # undamaged, it reads
    return frames[i]


def test_an_exr_cut_in_half(campaign):
    frame = a_frame(campaign)
    data = frame.path.read_bytes()
    frame.path.write_bytes(data[: len(data) // 2])
    # OpenEXR reads the header, fails on the pixel data (printing why) and hands back no parts.
    with pytest.raises(egogen.FormatError) as e:
        frame.read()
    assert str(e.value) == (
        f"{frame.path}: not a readable OpenEXR file (OpenEXR read no image from it: cut short or damaged)"
    )
    with pytest.raises(egogen.FormatError, match="not a readable OpenEXR file"):
        egogen.read_exr(frame.path)


def flipped(data: bytes, at: int, n: int = 16) -> bytes:
    """`data` with `n` bytes from `at` inverted."""
    return data[:at] + bytes(b ^ 0xFF for b in data[at : at + n]) + data[at + n :]


def test_an_exr_with_bytes_flipped_in_its_header_or_its_pixels(campaign):
    frame = a_frame(campaign)
    data = frame.path.read_bytes()

    # In the middle of the header: the `compression` attribute's name (OpenEXR's Python module
    # raises UnicodeDecodeError for it), then a channel's name (read as another channel).
    frame.path.write_bytes(flipped(data, data.index(b"compression\0"), 8))
    with pytest.raises(egogen.FormatError) as e:
        frame.read()
    assert str(e.value).startswith(f"{frame.path}: not a readable OpenEXR file (")
    assert e.value.__cause__ is not None

    at = data.index(b"depth.Z\0")
    frame.path.write_bytes(data[:at] + b"dXpth.Z" + data[at + 7 :])
    with pytest.raises(egogen.FormatError) as e:
        frame.read()
    assert str(e.value).startswith(f"{frame.path}: channel dXpth.Z: not a frame-file channel")

    # In the pixel data (ZIP-compressed): OpenEXR fails to decompress it. Not every damage is
    # found: of all 193 640 single-bit flips of one 24 205-byte frame file, 22 (in its
    # compressed pixels) decode to other pixels without an error; 1 847 change nothing read
    # (`tools/exr_bitflips.py`, docs/CAMPAIGNS.md). (The take's manifest has every file's SHA-256: `egogen-run CAMPAIGN --resume
    # --rehash` checks them.) 16 inverted bytes are found.
    frame.path.write_bytes(flipped(data, len(data) * 3 // 4))
    with pytest.raises(egogen.FormatError) as e:
        frame.read()
    assert str(e.value).startswith(f"{frame.path}: not a readable OpenEXR file")


def test_an_exr_of_another_size(campaign):
    import OpenEXR

    frame = a_frame(campaign)
    w, h = frame.camera_model["resolution_px"]
    # The frame file rewritten at half size: what a frame of another camera would be.
    with OpenEXR.File(str(frame.path), separate_channels=True) as f:
        header = dict(f.parts[0].header)
        channels = {n: np.ascontiguousarray(c.pixels[::2, ::2]) for n, c in f.parts[0].channels.items()}
    small = {k: v for k, v in header.items() if k in ("compression", "lineOrder", "type")}
    OpenEXR.File(small, channels).write(str(frame.path))
    assert egogen.read_exr(frame.path)["depth"].shape == (h // 2, w // 2)  # a readable EXR
    with pytest.raises(egogen.FormatError) as e:
        frame.read()
    assert str(e.value) == (
        f"{frame.path}: data window {w // 2}x{h // 2} pixels, expected {w}x{h} "
        f"({frame.annotations}: key camera.resolution_px)"
    )


def test_a_missing_frame_file(campaign):
    frame = a_frame(campaign, 2)
    frame.path.unlink()
    with pytest.raises(FileNotFoundError) as e:
        frame.read()
    assert str(frame.path) in str(e.value) and f"{frame.annotations}: key frames[2].file" in str(e.value)
    ds = egogen.FrameDataset(egogen.open(campaign))
    with pytest.raises(FileNotFoundError, match=frame.path.name):
        ds[2]


def test_a_damaged_index(campaign):
    index = campaign / "index.parquet"
    data = index.read_bytes()
    index.write_bytes(data[: len(data) // 2])
    with pytest.raises(egogen.FormatError) as e:
        egogen.open(campaign).index()
    assert str(index) in str(e.value) and "--resume` writes it again" in str(e.value)
