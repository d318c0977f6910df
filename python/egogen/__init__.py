"""Readers for what egogen writes.

    import egogen
    data = egogen.open("out/campaign")        # a campaign folder, or one take (dataset) folder
    for frame in data.frames(camera="camera-rgb"):
        image = frame.read()                  # {"rgb": HxWx3 (or "gray"), "depth": HxW, "segmentation": HxW, ...}
        frame.T_world_cam                     # 4x4, OpenCV camera frame to world (m, z up)
        frame.agents[0]["smplx"]["body_pose"] # SMPL-X parameters as the smplx package takes them
    table = data.index()                      # a campaign's index.parquet (needs pyarrow)
    ds = egogen.FrameDataset(data, channels=("colour", "depth"))  # PyTorch-style dataset

A take is a folder with `manifest.json`, `cameras/<camera>/annotations.json` and one EXR per
frame; a campaign is a folder with `campaign.json`, `index.parquet` and `takes/<id>/`.
Conventions (OpenCV camera frame, planar depth, pixel centres) are in each annotations file.
A damaged file raises `FormatError` (a ValueError) naming the file, the key and what was expected.
"""

from .reader import Campaign, FormatError, Frame, FrameDataset, Take, open, read_exr

__all__ = ["Campaign", "FormatError", "Frame", "FrameDataset", "Take", "open", "read_exr"]
__version__ = "0.1.0"
