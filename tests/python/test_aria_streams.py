"""projectaria-tools reads an egogen take's Aria streams with its own readers.

Run by .ci/run (which installs PyPI projectaria-tools, numpy and pytest):
    EGOGEN_BIN=target/debug/egogen python -m pytest tests/python
It makes a small take with `egogen synth` (3 agents, 6 s in the shipped apartment), exports it
with `egogen aria export` twice (ideal IMUs, then the device's errors) and checks every file.
"""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from projectaria_tools.core import calibration, mps

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(os.environ.get("EGOGEN_BIN", ROOT / "target" / "debug" / "egogen"))


def run(*args):
    done = subprocess.run([str(BIN), *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, f"egogen {' '.join(map(str, args))} failed:\n{done.stderr}"
    return done


@pytest.fixture(scope="module")
def take(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("aria")
    config = (ROOT / "configs" / "apartment3.toml").read_text()
    config = config.replace('"../', f'"{ROOT}/').replace("duration_s = 30.0", "duration_s = 6.0")
    config = config.replace(f'dir = "{ROOT}/out/apartment3"', f'dir = "{tmp / "take"}"')
    (tmp / "take.toml").write_text(config)
    run("synth", tmp / "take.toml", "--quiet")
    run("aria", "export", tmp / "take", "--out", tmp / "ideal", "--ideal-imu")
    run("aria", "export", tmp / "take", "--out", tmp / "device", "--seed", "7")
    run("aria", "export", tmp / "take", "--out", tmp / "hands", "--streams", "trajectory,hands")
    return tmp


def rot_angle(r):
    return float(np.arccos(np.clip((np.trace(r) - 1.0) / 2.0, -1.0, 1.0)))


def head_poses(take_dir, agent):
    frames = json.loads((take_dir / "agents" / agent / "cpf_trajectory.json").read_text())
    return [(f["time_s"], np.array(f["world_from_cpf"])) for f in frames]


def agents(take_dir):
    return sorted(p.name for p in (take_dir / "agents").iterdir())


def test_trajectory_passes_through_every_head_pose(take):
    for agent in agents(take / "take"):
        out = take / "ideal" / agent
        traj = mps.read_closed_loop_trajectory(str(out / "slam" / "closed_loop_trajectory.csv"))
        device = calibration.device_calibration_from_json(str(out / "device_calibration.json"))
        t_cpf_device = device.get_transform_cpf_sensor("camera-slam-left").to_matrix()
        by_us = {int(p.tracking_timestamp.total_seconds() * 1e6 + 0.5): p for p in traj}
        heads = head_poses(take / "take", agent)
        assert len(traj) == round(heads[-1][0] * 1000) + 1
        for time_s, world_from_cpf in heads:
            pose = by_us[round(time_s * 1e6)]
            world_from_cpf_csv = pose.transform_world_device.to_matrix() @ np.linalg.inv(t_cpf_device)
            assert np.linalg.norm(world_from_cpf_csv[:3, 3] - world_from_cpf[:3, 3]) < 1e-6
            assert rot_angle(world_from_cpf_csv[:3, :3].T @ world_from_cpf[:3, :3]) < 1e-6
            assert np.allclose(pose.gravity_world, [0.0, 0.0, -9.81])
            assert pose.graph_uid == agent


def test_velocities_agree_with_positions(take):
    agent = agents(take / "take")[0]
    traj = mps.read_closed_loop_trajectory(
        str(take / "ideal" / agent / "slam" / "closed_loop_trajectory.csv"))
    t = np.array([p.tracking_timestamp.total_seconds() for p in traj])
    m = np.array([p.transform_world_device.to_matrix() for p in traj])
    v_device = np.array([p.device_linear_velocity_device for p in traj])
    v_world = np.einsum("nij,nj->ni", m[:, :3, :3], v_device)
    # Five-point differences of the positions (samples 1 ms apart): off by h⁴/30 times the
    # fifth derivative, far below a µm/s where the head moves smoothly, up to a few tenths of a
    # mm/s at the motion's primitive seams (docs/ARIA.md). Central differences (h²/6 · jerk)
    # would measure the walk's jerk rather than the export.
    h = np.diff(t)
    assert np.allclose(h, h[0], rtol=1e-9, atol=1e-12), "samples 1 ms apart"
    x = m[:, :3, 3]
    v_diff = (-x[4:] + 8 * x[3:-1] - 8 * x[1:-3] + x[:-4]) / (12 * h[0])
    v_err = np.linalg.norm(v_diff - v_world[2:-2], axis=1)
    assert np.median(v_err) < 1e-8 and v_err.max() < 1e-2
    w = np.array([p.angular_velocity_device for p in traj])
    dr = np.einsum("nji,njk->nik", m[:-2, :3, :3], m[2:, :3, :3])
    angle = np.array([rot_angle(r) for r in dr]) / (t[2:] - t[:-2])
    w_err = np.abs(angle - np.linalg.norm(w[1:-1], axis=1))
    assert np.median(w_err) < 1e-5 and w_err.max() < 1e-2


def test_online_calibration_and_imus(take):
    agent = agents(take / "take")[0]
    rig = json.loads((ROOT / "camera_rigs" / "aria_gen1.json").read_text())
    for kind in ["ideal", "device"]:
        out = take / kind / agent
        lines = mps.read_online_calibration(str(out / "slam" / "online_calibration.jsonl"))
        assert len(lines) >= 7  # every second of the 6 s take, and its end
        cams = {c.get_label(): c for c in lines[0].camera_calibs}
        assert sorted(cams) == ["camera-rgb", "camera-slam-left", "camera-slam-right"]
        assert list(cams["camera-rgb"].get_image_size()) == [1408, 1408]
        imus = {i.get_label(): i for i in lines[0].imu_calibs}
        assert sorted(imus) == ["imu-left", "imu-right"]
        for entry in rig["imus"]:
            imu = imus[entry["name"]]
            stream = np.loadtxt(out / "imu" / f"{entry['name']}.csv", delimiter=",", skiprows=1)
            period_ns = np.diff(stream[:, 0])
            assert np.allclose(period_ns, 1e9 / entry["rate_hz"], atol=1.0)
            raw = stream[:, 1:4]
            rect = np.array([imu.raw_to_rectified_accel(a) for a in raw[::97]])
            # Walking heads: specific force about 1 g most of the time.
            assert 9.0 < np.median(np.linalg.norm(rect, axis=1)) < 11.0
            if kind == "ideal":
                assert np.allclose(imu.get_accel_model().get_rectification(), np.eye(3))
                ideal = raw
            else:
                ideal_stream = np.loadtxt(
                    take / "ideal" / agent / "imu" / f"{entry['name']}.csv",
                    delimiter=",", skiprows=1)
                ideal = ideal_stream[::97, 1:4]
                # Rectified device readings are the ideal ones up to noise and bias drift.
                assert np.abs(rect - ideal).max() < 0.1
                bias = entry["calibration"]["accel_bias_m_s2"]
                assert np.allclose(imu.get_accel_model().get_bias(), bias)


def test_cpf_of_the_device_calibration_is_the_rigs(take):
    agent = agents(take / "take")[0]
    device = calibration.device_calibration_from_json(
        str(take / "ideal" / agent / "device_calibration.json"))
    rig = json.loads((ROOT / "camera_rigs" / "aria_gen1.json").read_text())
    for cam in rig["cameras"]:
        t = device.get_transform_cpf_sensor(cam["name"]).to_matrix()
        assert np.allclose(t[:3, 3], cam["cpf_from_cam"]["translation_m"], atol=1e-9)
        assert np.allclose(t[:3, :3], np.array(cam["cpf_from_cam"]["rotation"]), atol=1e-9)


def test_eye_gaze_reads_and_points_where_the_depth_says(take, capfd):
    agent = agents(take / "take")[0]
    gaze = mps.read_eyegaze(str(take / "ideal" / agent / "eye_gaze" / "general_eye_gaze.csv"))
    # Read by the vergence reader projectaria-tools tries first: no fallback to the legacy one.
    printed = capfd.readouterr()
    assert "Failed to parse" not in printed.err + printed.out, printed.err
    g = gaze[10]
    assert g.vergence.tx_left_eye == pytest.approx(0.0315) and g.vergence.tx_right_eye == pytest.approx(-0.0315)
    assert g.vergence.left_yaw < g.yaw < g.vergence.right_yaw
    # The reader's own vergence geometry: the eyes' rays cross at the written depth and yaw.
    depth_from_eyes, yaw_from_eyes, _ = mps.compute_depth_and_combined_gaze_direction(
        g.vergence.left_yaw, g.vergence.right_yaw, g.pitch)
    assert depth_from_eyes == pytest.approx(g.depth, rel=1e-3) and yaw_from_eyes == pytest.approx(g.yaw, abs=1e-5)
    assert len(gaze) == int(np.floor(head_poses(take / "take", agent)[-1][0] * 30 + 1e-9)) + 1
    yaw = np.array([g.yaw for g in gaze])
    pitch = np.array([g.pitch for g in gaze])
    depth = np.array([g.depth for g in gaze])
    assert gaze[0].session_uid == agent
    # Within the eyes' range (30° from straight ahead), at a surface in the apartment.
    d = np.stack([np.tan(yaw), np.tan(pitch), np.ones_like(yaw)], axis=1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    assert np.degrees(np.arccos(d[:, 2])).max() < 30.0 + 1e-4  # read as float32
    assert 0.1 < depth.min() and depth.max() < 20.0
    point = np.array(mps.get_eyegaze_point_at_depth(gaze[10].yaw, gaze[10].pitch, gaze[10].depth))
    assert abs(np.linalg.norm(point) - gaze[10].depth) < 1e-4


def test_hand_tracking_reads_back_where_the_bodies_hands_are(take):
    """MPS hand tracking by projectaria-tools' reader: a row per motion frame, 21 landmarks a
    hand in the device frame at the trajectory's pose of the same microsecond; the wrist
    landmark is the wrist pose's origin, the bones between finger joints keep their length
    (a rigid skeleton seen from a moving head), the normals are unit vectors, and the hands
    hang below the head and move with the fingers."""
    from projectaria_tools.core.mps import hand_tracking as ht
    for agent in agents(take / "take"):
        out = take / "hands" / agent
        rows = ht.read_hand_tracking_results(str(out / "hand_tracking" / "hand_tracking_results.csv"))
        heads = head_poses(take / "take", agent)
        assert len(rows) == len(heads)
        traj = mps.read_closed_loop_trajectory(str(out / "slam" / "closed_loop_trajectory.csv"))
        by_us = {int(p.tracking_timestamp.total_seconds() * 1e6 + 0.5): p for p in traj}
        bones = {}
        for row, (time_s, world_from_cpf) in zip(rows, heads):
            us = int(row.tracking_timestamp.total_seconds() * 1e6 + 0.5)
            assert us == round(time_s * 1e6)
            world_from_device = by_us[us].transform_world_device.to_matrix()
            for side, hand in [("left", row.left_hand), ("right", row.right_hand)]:
                assert hand.confidence == 1.0
                pts = np.array(hand.landmark_positions_device)
                assert pts.shape == (21, 3)
                wrist = hand.transform_device_wrist.to_matrix()
                assert np.linalg.norm(pts[int(ht.HandLandmark.WRIST)] - wrist[:3, 3]) < 1e-9
                normals = hand.wrist_and_palm_normal_device
                assert abs(np.linalg.norm(normals.palm_normal_device) - 1.0) < 1e-9
                assert abs(np.linalg.norm(normals.wrist_normal_device) - 1.0) < 1e-9
                world = (world_from_device[:3, :3] @ pts.T).T + world_from_device[:3, 3]
                below = world_from_cpf[2, 3] - world[:, 2]
                assert below.min() > 0.2, f"{agent} {side}: a hand above the eyes"
                for a, b in [(8, 9), (9, 10), (11, 12), (14, 15), (17, 18), (6, 7)]:
                    bones.setdefault((side, a, b), []).append(np.linalg.norm(world[a] - world[b]))
        for key, lengths in bones.items():
            assert np.ptp(lengths) < 1e-9, f"{agent} {key}: bone length varies by {np.ptp(lengths)}"
