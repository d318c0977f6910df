"""Real clients read an egogen EuRoC export: evo's EuRoC reader gives the take's device poses,
PyYAML reads every sensor.yaml with the keys and types EuRoC's have.

Run by `cargo test --test euroc_export euroc_clients_read_the_export`, which renders a tiny take,
exports a wearer and sets EGOGEN_EUROC_DIR (the export), EGOGEN_EUROC_TAKE (the take) and
EGOGEN_EUROC_WEARER; its Python has evo, PyYAML, numpy and pytest. Elsewhere (another test's
Python, or without those variables) the module is skipped.
"""

import json
import os
from pathlib import Path

import pytest

np = pytest.importorskip("numpy")
yaml = pytest.importorskip("yaml")
file_interface = pytest.importorskip("evo.tools.file_interface")

if "EGOGEN_EUROC_DIR" not in os.environ:
    pytest.skip("EGOGEN_EUROC_DIR not set (run by tests/euroc_export.rs)", allow_module_level=True)

MAV0 = Path(os.environ["EGOGEN_EUROC_DIR"]) / "mav0"
TAKE = Path(os.environ["EGOGEN_EUROC_TAKE"])
WEARER = os.environ["EGOGEN_EUROC_WEARER"]
ROOT = Path(__file__).resolve().parents[2]


def rot_angle(r):
    return float(np.arccos(np.clip((np.trace(r) - 1.0) / 2.0, -1.0, 1.0)))


def rig_pose(entry):
    m = np.eye(4)
    m[:3, :3] = np.array(entry["rotation"])
    m[:3, 3] = entry["translation_m"]
    return m


def t_bs(doc):
    t = doc["T_BS"]
    assert t["rows"] == 4 and t["cols"] == 4 and len(t["data"]) == 16
    assert all(isinstance(v, float) for v in t["data"])
    return np.array(t["data"]).reshape(4, 4)


def test_evo_reads_the_device_poses_of_the_take():
    traj = file_interface.read_euroc_csv_trajectory(str(MAV0 / "state_groundtruth_estimate0" / "data.csv"))
    imu = np.loadtxt(MAV0 / "imu0" / "data.csv", delimiter=",", comments="#")
    assert traj.num_poses == len(imu)
    assert np.array_equal(traj.timestamps, imu[:, 0] / 1e9)
    assert np.all(np.diff(traj.timestamps) > 0)
    by_ns = {round(t * 1e9): pose for t, pose in zip(traj.timestamps, traj.poses_se3)}
    rig = json.loads((ROOT / "camera_rigs" / "aria_gen1.json").read_text())
    cpf_from_imu = rig_pose(next(i for i in rig["imus"] if i["name"] == "imu-right")["cpf_from_imu"])
    checked = 0
    for k, side in enumerate(["left", "right"]):
        name = f"{WEARER}_camera-slam-{side}"
        ann = json.loads((TAKE / "cameras" / name / "annotations.json").read_text())
        cpf_from_cam = rig_pose(next(c for c in rig["cameras"] if c["name"] == f"camera-slam-{side}")["cpf_from_cam"])
        sensor = yaml.safe_load((MAV0 / f"cam{k}" / "sensor.yaml").read_text())
        imu_from_cam = t_bs(sensor)
        assert np.allclose(imu_from_cam, np.linalg.inv(cpf_from_imu) @ cpf_from_cam, atol=1e-12)
        rows = np.loadtxt(MAV0 / f"cam{k}" / "data.csv", delimiter=",", skiprows=1, dtype=str, ndmin=2)
        assert len(rows) == len(ann["frames"])
        for (ns, file), frame in zip(rows, ann["frames"]):
            assert file == f"{ns}.png" and (MAV0 / f"cam{k}" / "data" / file).is_file()
            assert int(ns) == round(frame["frame"] * 1e9 / ann["frame_rate_hz"])
            world_from_cam = np.array(frame["T_world_cam"])
            expected = world_from_cam @ np.linalg.inv(cpf_from_cam) @ cpf_from_imu
            pose = by_ns[int(ns)]
            assert np.linalg.norm(pose[:3, 3] - expected[:3, 3]) < 1e-9
            assert rot_angle(pose[:3, :3].T @ expected[:3, :3]) < 1e-7  # arccos near 1
            assert np.allclose(pose @ imu_from_cam, world_from_cam, atol=1e-9)
            checked += 1
    assert checked >= 8


def test_every_yaml_parses_with_euroc_keys():
    body = yaml.safe_load((MAV0 / "body.yaml").read_text())
    assert isinstance(body["comment"], str)
    imu = yaml.safe_load((MAV0 / "imu0" / "sensor.yaml").read_text())
    assert imu["sensor_type"] == "imu"
    assert np.array_equal(t_bs(imu), np.eye(4))
    for key in ["rate_hz", "gyroscope_noise_density", "gyroscope_random_walk",
                "accelerometer_noise_density", "accelerometer_random_walk"]:
        assert isinstance(imu[key], float) and imu[key] > 0, key
    assert imu["rate_hz"] == 1000.0
    for k in [0, 1]:
        cam = yaml.safe_load((MAV0 / f"cam{k}" / "sensor.yaml").read_text())
        assert cam["sensor_type"] == "camera"
        assert cam["camera_model"] == "pinhole"
        assert cam["distortion_model"] == "equidistant"
        assert all(isinstance(v, int) for v in cam["resolution"]) and len(cam["resolution"]) == 2
        assert all(isinstance(v, float) for v in cam["intrinsics"]) and len(cam["intrinsics"]) == 4
        assert all(isinstance(v, float) for v in cam["distortion_coefficients"])
        assert len(cam["distortion_coefficients"]) == 4
        assert isinstance(cam["rate_hz"], float)
        r = t_bs(cam)
        assert np.allclose(r[:3, :3].T @ r[:3, :3], np.eye(3), atol=1e-12)
    gt = yaml.safe_load((MAV0 / "state_groundtruth_estimate0" / "sensor.yaml").read_text())
    assert np.array_equal(t_bs(gt), np.eye(4))
