"""Takes, campaigns and their frames (see the package docs)."""

from __future__ import annotations

import builtins
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator, Optional, Sequence

import numpy as np

# EXR channels of a frame file, grouped into arrays: name -> (channels, dtype).
_GROUPS = {
    "rgb": (["rgb.R", "rgb.G", "rgb.B"], np.float32),
    "alpha": (["rgb.A"], np.float32),
    "gray": (["gray.Y"], np.float32),
    "valid": (["valid.V"], np.float32),
    "depth": (["depth.Z"], np.float32),
    "depth_noisy": (["depth_noisy.Z"], np.float32),
    "normal": (["normal.X", "normal.Y", "normal.Z"], np.float32),
    "position": (["position.X", "position.Y", "position.Z"], np.float32),
    "segmentation": (["segmentation.id"], np.uint32),
    "flow_forward": (["flow_forward.X", "flow_forward.Y"], np.float32),
    "flow_backward": (["flow_backward.X", "flow_backward.Y"], np.float32),
}


def read_exr(path, channels: Optional[Sequence[str]] = None) -> dict:
    """Reads an egogen frame file into arrays by group name (`rgb` HxWx3, `gray` HxW of a
    monochrome camera, `depth` HxW, `segmentation` HxW uint32, ...); `channels` picks groups
    (default: all it holds), `colour` standing for `rgb` or `gray`, whichever the camera has."""
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        raw = {name: ch.pixels for name, ch in f.parts[0].channels.items()}
    out = {}
    if channels is not None and "colour" in channels:
        # The camera's colour whichever it is: `rgb` (HxWx3) or a monochrome camera's `gray`.
        group = "rgb" if "rgb.R" in raw else "gray"
        out.update(read_exr_groups(path, raw, [group]))
        channels = [c for c in channels if c != "colour"]
        out["colour"] = out.pop(group)
    out.update(read_exr_groups(path, raw, channels))
    return out


def read_exr_groups(path, raw: dict, channels) -> dict:
    out = {}
    for group, (names, dtype) in _GROUPS.items():
        if channels is not None and group not in channels:
            continue
        if not all(n in raw for n in names):
            if channels is not None:
                raise KeyError(f"{path}: no `{group}` in this frame file (it holds {sorted(raw)})")
            continue
        planes = [np.asarray(raw[n]).astype(dtype, copy=False) for n in names]
        out[group] = planes[0] if len(planes) == 1 else np.stack(planes, axis=-1)
    return out


@dataclass
class Frame:
    """One rendered frame of one camera."""

    take: str
    camera: str
    index: int
    time_s: float
    path: Path
    T_world_cam: np.ndarray
    agents: list
    colour_exposure: Optional[float]
    camera_model: dict = field(repr=False)

    def read(self, channels: Optional[Sequence[str]] = None) -> dict:
        """The frame's pixels by group (see `read_exr`)."""
        return read_exr(self.path, channels)

    def smplx(self, agent: int | str = 0) -> dict:
        """An agent's SMPL-X parameters as numpy arrays (`betas`, `global_orient`, `body_pose`,
        ..., `transl`), ready for `smplx.create(...)(**{k: torch.tensor(v)[None] ...})`."""
        a = self._agent(agent)
        return {k: np.asarray(v, dtype=np.float64) for k, v in a["smplx"].items()}

    def joints_2d(self, agent: int | str = 0) -> np.ndarray:
        """An agent's 55 joints in pixels (NaN outside the valid field of view)."""
        a = self._agent(agent)
        return np.array([j if j is not None else [np.nan, np.nan] for j in a["joints_2d"]], dtype=np.float64)

    def _agent(self, agent):
        if isinstance(agent, str):
            for a in self.agents:
                if a["name"] == agent:
                    return a
            raise KeyError(f"{self.take}/{self.camera} frame {self.index}: no agent {agent!r}")
        return self.agents[agent]


class Take:
    """One take: an egogen-run dataset folder (`manifest.json`, `cameras/`, `sequence/`)."""

    def __init__(self, path, name: Optional[str] = None):
        self.path = Path(path)
        if not (self.path / "manifest.json").is_file():
            raise FileNotFoundError(f"{self.path}: no manifest.json (not a finished egogen take)")
        self.name = name if name is not None else self.path.name
        self._annotations = {}

    @property
    def cameras(self) -> list:
        """The take's camera names."""
        root = self.path / "cameras"
        return sorted(p.name for p in root.iterdir() if (p / "annotations.json").is_file())

    def annotations(self, camera: str) -> dict:
        """A camera's `annotations.json` (camera model, conventions, ids, every frame)."""
        if camera not in self._annotations:
            p = self.path / "cameras" / camera / "annotations.json"
            if not p.is_file():
                raise KeyError(f"{self.path}: no camera {camera!r} (cameras: {self.cameras})")
            with builtins.open(p) as f:
                self._annotations[camera] = json.load(f)
        return self._annotations[camera]

    def frames(self, camera: Optional[str] = None) -> Iterator[Frame]:
        """Every frame, camera by camera (or of one camera), in frame order."""
        for cam in [camera] if camera is not None else self.cameras:
            doc = self.annotations(cam)
            for f in doc["frames"]:
                yield Frame(
                    take=self.name,
                    camera=cam,
                    index=f["frame"],
                    time_s=f["time_s"],
                    path=self.path / "cameras" / cam / f["file"],
                    T_world_cam=np.array(f["T_world_cam"], dtype=np.float64),
                    agents=f["agents"],
                    colour_exposure=f.get("colour_exposure"),
                    camera_model=doc["camera"],
                )

    def camera_poses(self, camera: str) -> np.ndarray:
        """The camera's T_world_cam for every rendered frame, N x 4 x 4."""
        return np.stack([f.T_world_cam for f in self.frames(camera)])

    def segmentation_ids(self, camera: Optional[str] = None) -> dict:
        """Segmentation id -> name (scene objects and agents)."""
        doc = self.annotations(camera or self.cameras[0])
        return {e["id"]: e["name"] for e in doc["segmentation_ids"]}

    def segmentation_labels(self, camera: Optional[str] = None) -> dict:
        """Segmentation id -> class label, for the objects whose scene file names one (a
        Replica scan's `info_semantic.json`); ids without a label are left out."""
        doc = self.annotations(camera or self.cameras[0])
        return {e["id"]: e["label"] for e in doc["segmentation_ids"] if "label" in e}

    def __len__(self):
        return sum(len(self.annotations(c)["frames"]) for c in self.cameras)

    def __repr__(self):
        return f"Take({str(self.path)!r}, cameras={self.cameras})"


class Campaign:
    """A campaign folder: `campaign.json`, `index.parquet`, finished takes in `takes/<id>/`."""

    def __init__(self, path):
        self.path = Path(path)
        state = self.path / "campaign.json"
        if not state.is_file():
            raise FileNotFoundError(f"{self.path}: no campaign.json (not an egogen campaign)")
        with builtins.open(state) as f:
            self.state = json.load(f)

    @property
    def take_ids(self) -> list:
        """The finished takes, in campaign order."""
        return [t["id"] for t in self.state["takes"] if t["status"] == "complete"]

    def take(self, take_id: str) -> Take:
        return Take(self.path / "takes" / take_id, name=take_id)

    def takes(self) -> Iterator[Take]:
        for t in self.take_ids:
            yield self.take(t)

    def frames(self, camera: Optional[str] = None) -> Iterator[Frame]:
        """Every frame of every finished take, in campaign order."""
        for t in self.takes():
            yield from t.frames(camera)

    def index(self):
        """`index.parquet` as a pyarrow Table (one row per frame: take, scene, seed, camera,
        wearer, frame, time_s, file, agents_in_view, colour_exposure)."""
        import pyarrow.parquet as pq

        return pq.read_table(self.path / "index.parquet")

    def __len__(self):
        return sum(t.get("frames") or 0 for t in self.state["takes"] if t["status"] == "complete")

    def __repr__(self):
        return f"Campaign({str(self.path)!r}, takes={len(self.take_ids)})"


def open(path):
    """A campaign (a folder with campaign.json) or a take (a folder with manifest.json)."""
    p = Path(path)
    if (p / "campaign.json").is_file():
        return Campaign(p)
    return Take(p)


try:  # A torch Dataset when torch is there; the same interface without it.
    from torch.utils.data import Dataset as _Base
except ImportError:  # pragma: no cover - depends on the environment
    _Base = object


class FrameDataset(_Base):
    """Frames of a take or campaign as a map-style dataset: item i is a dict of the frame's
    pixel groups (`channels`), `T_world_cam`, its take, camera, frame index and time, and the
    SMPL-X parameters of every agent (`smplx`: name -> dict of arrays)."""

    def __init__(self, data, camera: Optional[str] = None, channels: Sequence[str] = ("colour",), transform=None):
        self.frames = list(data.frames(camera))
        self.channels = tuple(channels)
        self.transform = transform

    def __len__(self):
        return len(self.frames)

    def __getitem__(self, i):
        f = self.frames[i]
        item = dict(f.read(self.channels))
        item.update(
            take=f.take,
            camera=f.camera,
            frame=f.index,
            time_s=f.time_s,
            T_world_cam=f.T_world_cam,
            smplx={a["name"]: f.smplx(a["name"]) for a in f.agents},
        )
        return self.transform(item) if self.transform else item
