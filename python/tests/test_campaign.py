"""The reader against a campaign egogen-run made (EGOGEN_CAMPAIGN), checked against the files
themselves: every finished take, every frame in the index, pixels, poses and SMPL-X."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

import egogen

CAMPAIGN = Path(os.environ.get("EGOGEN_CAMPAIGN", ""))
pytestmark = pytest.mark.skipif(not (CAMPAIGN / "campaign.json").is_file(), reason="EGOGEN_CAMPAIGN not set")


def test_opens_the_campaign_and_its_takes():
    c = egogen.open(CAMPAIGN)
    assert isinstance(c, egogen.Campaign)
    state = json.loads((CAMPAIGN / "campaign.json").read_text())
    assert c.take_ids == [t["id"] for t in state["takes"] if t["status"] == "complete"]
    assert len(c.take_ids) >= 3
    for take in c.takes():
        assert take.cameras == ["camera-slam-left"]
        assert isinstance(egogen.open(take.path), egogen.Take)


def test_the_index_lists_every_frame_file():
    c = egogen.open(CAMPAIGN)
    table = c.index().to_pylist()
    files = sorted(str(p.relative_to(CAMPAIGN)) for p in CAMPAIGN.glob("takes/*/cameras/*/frame_*.exr"))
    assert sorted(r["file"] for r in table) == files
    frames = list(c.frames())
    assert len(frames) == len(table) == len(c)
    for row, frame in zip(table, frames):
        assert (row["take"], row["camera"], row["frame"]) == (frame.take, frame.camera, frame.index)
        assert row["time_s"] == pytest.approx(frame.time_s)
        assert row["agents_in_view"] == sum(1 for a in frame.agents if a["in_view"] and not a["wearer"])


def test_frames_hold_pixels_poses_and_smplx():
    c = egogen.open(CAMPAIGN)
    frame = next(c.frames())
    px = frame.read()
    h, w = px["depth"].shape
    # The SLAM camera is monochrome: `gray`, and `colour` stands for it.
    assert "rgb" not in px and px["gray"].shape == (h, w)
    assert px["segmentation"].dtype == np.uint32
    assert np.isfinite(px["gray"]).all() and (px["depth"] >= 0).all()
    assert np.array_equal(frame.read(["colour"])["colour"], px["gray"])
    T = frame.T_world_cam
    assert T.shape == (4, 4) and np.allclose(T[3], [0, 0, 0, 1])
    assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-9)
    s = frame.smplx(0)
    assert s["body_pose"].shape == (63,) and s["transl"].shape == (3,)
    # The wearer's camera sits at its eyes: within 0.3 m of its head joint (15).
    wearer = next(a for a in frame.agents if a["wearer"])
    assert np.linalg.norm(T[:3, 3] - np.array(wearer["joints_3d"][15])) < 0.3
    ids = c.take(frame.take).segmentation_ids()
    assert set(np.unique(px["segmentation"])) <= set(ids) | {0}


def test_frame_dataset_items():
    ds = egogen.FrameDataset(egogen.open(CAMPAIGN), channels=("colour", "depth"))
    assert len(ds) == len(list(egogen.open(CAMPAIGN).frames()))
    item = ds[len(ds) - 1]
    assert set(item) >= {"colour", "depth", "T_world_cam", "take", "camera", "frame", "smplx"}
    assert all("global_orient" in v for v in item["smplx"].values())
