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
    "body_part": (["segmentation.part"], np.uint32),
    "garment": (["segmentation.garment"], np.uint32),
    "flow_forward": (["flow_forward.X", "flow_forward.Y"], np.float32),
    "flow_backward": (["flow_backward.X", "flow_backward.Y"], np.float32),
}
# Every channel a frame file may hold, with the type egogen writes it in.
_CHANNELS = {name: np.dtype(dtype) for names, dtype in _GROUPS.values() for name in names}


class FormatError(ValueError):
    """A file egogen wrote is damaged or not what it should be; the message names the file, the
    key or field, and what was expected."""


def _found(value) -> str:
    """A short description of a JSON value for an error message."""
    text = json.dumps(value)
    return "found " + (text if len(text) <= 60 else text[:57] + "...")


def _field(obj: dict, key: str, file, where: str, expected: str, types):
    """obj[key] when it is there and of `types` (true and false are not numbers); FormatError
    naming the file and key if not."""
    name = f"{where}.{key}" if where else key
    if key not in obj:
        raise FormatError(f"{file}: key {name}: missing (expected {expected})")
    value = obj[key]
    if not isinstance(value, types) or isinstance(value, bool):
        raise FormatError(f"{file}: key {name}: {_found(value)} (expected {expected})")
    return value


def _entry(items: list, i: int, file, where: str, expected: str) -> dict:
    """items[i] when it is a JSON object; FormatError naming the file and key if not."""
    if not isinstance(items[i], dict):
        raise FormatError(f"{file}: key {where}[{i}]: {_found(items[i])} (expected {expected})")
    return items[i]


def _load_json(path: Path, expected: str) -> dict:
    """A JSON object from `path`; FormatError naming the file when it is not one."""
    try:
        with builtins.open(path, "rb") as f:
            doc = json.load(f)
    except json.JSONDecodeError as e:
        where = f"line {e.lineno} column {e.colno}"
        raise FormatError(f"{path}: not valid JSON ({e.msg}: {where}); expected {expected}") from e
    except UnicodeDecodeError as e:
        raise FormatError(f"{path}: not valid JSON (not UTF-8 text at byte {e.start}); expected {expected}") from e
    if not isinstance(doc, dict):
        raise FormatError(f"{path}: {_found(doc)}, not a JSON object; expected {expected}")
    return doc


def read_exr(path, channels: Optional[Sequence[str]] = None) -> dict:
    """Reads an egogen frame file into arrays by group name (`rgb` HxWx3, `gray` HxW of a
    monochrome camera, `depth` HxW, `segmentation` HxW uint32, ...); `channels` picks groups
    (default: all it holds), `colour` standing for `rgb` or `gray`, whichever the camera has.
    FileNotFoundError when there is no such file, FormatError when it is not a readable
    OpenEXR file."""
    return _read_exr(path, channels, None)


def _open_exr(path) -> tuple:
    """The channels of an EXR file by name and its data window's (width, height)."""
    import OpenEXR

    if not Path(path).is_file():
        raise FileNotFoundError(f"{path}: no such file")
    raw = None
    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            # No parts is what OpenEXR's Python module gives when it cannot read a part's pixels
            # (it prints why): the file is cut short or damaged.
            if f.parts:
                lo, hi = f.parts[0].header["dataWindow"]
                raw = {name: ch.pixels for name, ch in f.parts[0].channels.items()}
    except Exception as e:  # whatever OpenEXR raises for a damaged file: RuntimeError, ValueError, ...
        raise FormatError(f"{path}: not a readable OpenEXR file ({type(e).__name__}: {e})") from e
    if raw is None:
        raise FormatError(f"{path}: not a readable OpenEXR file (OpenEXR read no image from it: cut short or damaged)")
    size = (int(hi[0]) - int(lo[0]) + 1, int(hi[1]) - int(lo[1]) + 1)
    # As egogen writes them: only frame-file channels, each of its type and the data window's
    # size, each group whole. (A damaged header can name another channel or type.)
    for name, px in raw.items():
        if name not in _CHANNELS:
            raise FormatError(f"{path}: channel {name}: not a frame-file channel (expected those of {sorted(_GROUPS)})")
        if not isinstance(px, np.ndarray) or px.dtype != _CHANNELS[name]:
            raise FormatError(f"{path}: channel {name}: {getattr(px, 'dtype', px)} pixels (expected {_CHANNELS[name]})")
        if px.shape != (size[1], size[0]):
            raise FormatError(f"{path}: channel {name}: {px.shape[1::-1]} pixels, not its data window's {size}")
    for group, (names, _) in _GROUPS.items():
        missing = [n for n in names if n not in raw]
        if missing and len(missing) < len(names):
            raise FormatError(f"{path}: channel {missing[0]}: missing (the `{group}` group is {names})")
    return raw, size


def _read_exr(path, channels, expect) -> dict:
    """`read_exr`, with `expect` = (width, height, where that size comes from) checked against
    the file's data window when given."""
    raw, (w, h) = _open_exr(path)
    if expect is not None and (w, h) != tuple(expect[:2]):
        raise FormatError(f"{path}: data window {w}x{h} pixels, expected {expect[0]}x{expect[1]} ({expect[2]})")
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
    # Where the frame is listed: its camera's annotations.json and its place in `frames`.
    annotations: Optional[Path] = field(default=None, repr=False, compare=False)
    entry: Optional[int] = field(default=None, repr=False, compare=False)

    def read(self, channels: Optional[Sequence[str]] = None) -> dict:
        """The frame's pixels by group (see `read_exr`); FormatError when the file is damaged or
        not of this camera's size, FileNotFoundError when it is missing."""
        if self.annotations is None:
            return read_exr(self.path, channels)
        if not self.path.is_file():
            key = f"{self.annotations}: key frames[{self.entry}].file"
            raise FileNotFoundError(f"{self.path}: no such frame file (named by {key})")
        w, h = self.camera_model["resolution_px"]
        return _read_exr(self.path, channels, (w, h, f"{self.annotations}: key camera.resolution_px"))

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
            doc = _load_json(p, "a camera's annotations as egogen-run writes them")
            _field(doc, "frames", p, "", "a list of frames", list)
            cam = _field(doc, "camera", p, "", "the camera model", dict)
            size = _field(cam, "resolution_px", p, "camera", "[width, height] in pixels", list)
            if len(size) != 2 or not all(isinstance(n, int) and not isinstance(n, bool) and n > 0 for n in size):
                raise FormatError(f"{p}: key camera.resolution_px: {_found(size)} (expected [width, height] in pixels)")
            self._annotations[camera] = doc
        return self._annotations[camera]

    def frames(self, camera: Optional[str] = None) -> Iterator[Frame]:
        """Every frame, camera by camera (or of one camera), in frame order."""
        for cam in [camera] if camera is not None else self.cameras:
            doc = self.annotations(cam)
            for i in range(len(doc["frames"])):
                yield self._frame(cam, doc, i)

    def _frame(self, camera: str, doc: dict, i: int) -> Frame:
        """Frame `i` of a camera's annotations; FormatError naming the key it lacks."""
        p = self.path / "cameras" / camera / "annotations.json"
        f = _entry(doc["frames"], i, p, "frames", "a frame")
        where = f"frames[{i}]"
        file = _field(f, "file", p, where, "the frame file's name", str)
        T = _field(f, "T_world_cam", p, where, "a 4x4 matrix", list)
        try:
            T = np.array(T, dtype=np.float64)
        except (TypeError, ValueError):
            T = None
        if T is None or T.shape != (4, 4) or not np.isfinite(T).all():
            raise FormatError(f"{p}: key {where}.T_world_cam: {_found(f['T_world_cam'])} (expected a 4x4 matrix)")
        agents = _field(f, "agents", p, where, "a list of agents", list)
        for j in range(len(agents)):
            a = _entry(agents, j, p, f"{where}.agents", "an agent")
            _field(a, "name", p, f"{where}.agents[{j}]", "the agent's name", str)
            _field(a, "smplx", p, f"{where}.agents[{j}]", "SMPL-X parameters by name", dict)
            _field(a, "joints_2d", p, f"{where}.agents[{j}]", "55 joints in pixels", list)
        exposure = f.get("colour_exposure")
        if exposure is not None and not isinstance(exposure, (int, float)):
            raise FormatError(f"{p}: key {where}.colour_exposure: {_found(exposure)} (expected a number or null)")
        return Frame(
            take=self.name,
            camera=camera,
            index=_field(f, "frame", p, where, "the frame number", int),
            time_s=_field(f, "time_s", p, where, "the time in seconds", (int, float)),
            path=self.path / "cameras" / camera / file,
            T_world_cam=T,
            agents=agents,
            colour_exposure=exposure,
            camera_model=doc["camera"],
            annotations=p,
            entry=i,
        )

    def camera_poses(self, camera: str) -> np.ndarray:
        """The camera's T_world_cam for every rendered frame, N x 4 x 4."""
        return np.stack([f.T_world_cam for f in self.frames(camera)])

    def segmentation_ids(self, camera: Optional[str] = None) -> dict:
        """Segmentation id -> name (scene objects and agents)."""
        return {e["id"]: e["name"] for e in self._segmentation_ids(camera)}

    def segmentation_labels(self, camera: Optional[str] = None) -> dict:
        """Segmentation id -> class label, for the objects whose scene file names one (a
        Replica scan's `info_semantic.json`); ids without a label are left out."""
        return {e["id"]: e["label"] for e in self._segmentation_ids(camera) if "label" in e}

    def _segmentation_ids(self, camera: Optional[str]) -> list:
        """The annotations' `segmentation_ids`, each checked for its `id` and `name`."""
        camera = camera or self.cameras[0]
        p = self.path / "cameras" / camera / "annotations.json"
        ids = _field(self.annotations(camera), "segmentation_ids", p, "", "a list of {id, name}", list)
        for i in range(len(ids)):
            e = _entry(ids, i, p, "segmentation_ids", "{id, name}")
            _field(e, "id", p, f"segmentation_ids[{i}]", "a segmentation id", int)
            _field(e, "name", p, f"segmentation_ids[{i}]", "a name", str)
        return ids

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
        self.state = _load_json(state, "a campaign's state as egogen-run writes it")
        takes = _field(self.state, "takes", state, "", "a list of takes", list)
        for i in range(len(takes)):
            t = _entry(takes, i, state, "takes", "a take")
            _field(t, "id", state, f"takes[{i}]", "the take's id", str)
            _field(t, "status", state, f"takes[{i}]", "planned, complete or failed", str)
            if t.get("frames") is not None:
                _field(t, "frames", state, f"takes[{i}]", "a number of frames or null", int)

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
        wearer, frame, time_s, file, agents_in_view, colour_exposure, and in takes with
        activities the wearer's `activity` and `activity_phase` and `activities_in_view`; null
        where people only walk)."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        p = self.path / "index.parquet"
        again = f"`egogen-run {self.state.get('config', 'CAMPAIGN.toml')} --resume` writes it again"
        if not p.is_file():
            raise FileNotFoundError(f"{p}: no such file ({again})")
        try:
            return pq.read_table(p)
        except (PermissionError, FileNotFoundError):
            raise
        except (pa.ArrowException, OSError) as e:
            raise FormatError(f"{p}: not a readable Parquet table ({e}); {again}") from e

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
