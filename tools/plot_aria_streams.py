"""The picture of a wearer's Aria streams in docs/ARIA.md (docs/aria_streams.png).

    egogen synth configs/apartment3.toml
    egogen aria export out/apartment3 --out out/apartment3_aria --gaze-rate-hz 200
    python tools/plot_aria_streams.py out/apartment3 out/apartment3_aria crowd_00 docs/aria_streams.png [--replace]

Needs projectaria-tools, numpy, matplotlib. Left: the device trajectory from above with a gaze
ray every 0.5 s (to its depth), the other agents' paths in grey. Middle: imu-right's
accelerometer and gyroscope over the first 10 s. Right: the gaze's angle to the head's forward
direction; fixation durations found in the 200 Hz gaze by a velocity threshold on the gaze
direction in the world (I-VT, 30 deg/s, as head-free eye-tracking analysis does), beside the
model's log-normal and Rayner's 330 ms.
"""

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from projectaria_tools.core import calibration, mps

import arguments
import outputs


def main(take, aria, wearer, out, replace=False):
    outputs.check_new(out, "OUT", replace)
    outputs.check_outside(out, "OUT", take, "the take")
    outputs.check_outside(out, "OUT", aria, "the Aria export")
    take, aria = Path(take), Path(aria) / wearer
    traj = mps.read_closed_loop_trajectory(str(aria / "slam" / "closed_loop_trajectory.csv"))
    device = calibration.device_calibration_from_json(str(aria / "device_calibration.json"))
    t_device_cpf = np.linalg.inv(device.get_transform_cpf_sensor("camera-slam-left").to_matrix())
    gaze = mps.read_eyegaze(str(aria / "eye_gaze" / "general_eye_gaze.csv"))
    imu = np.loadtxt(aria / "imu" / "imu-right.csv", delimiter=",", skiprows=1)

    fig, ax = plt.subplots(1, 5, figsize=(24, 4.8))
    t_traj = np.array([p.tracking_timestamp.total_seconds() for p in traj])
    pos = np.array([p.transform_world_device.translation()[0] for p in traj])
    for d in sorted((take / "agents").iterdir()):
        if d.name == wearer:
            continue
        frames = json.loads((d / "cpf_trajectory.json").read_text())
        xy = np.array([[f["world_from_cpf"][0][3], f["world_from_cpf"][1][3]] for f in frames])
        ax[0].plot(xy[:, 0], xy[:, 1], color="0.75", lw=1)
    ax[0].plot(pos[:, 0], pos[:, 1], color="tab:blue", lw=1.5, label=f"{wearer} device")
    for g in gaze[::100]:  # 200 Hz: every 0.5 s
        t = g.tracking_timestamp.total_seconds()
        k = min(int(round(t * 1000)), len(traj) - 1)
        world_from_cpf = traj[k].transform_world_device.to_matrix() @ t_device_cpf
        p = np.array(mps.get_eyegaze_point_at_depth(g.yaw, g.pitch, g.depth))
        a = world_from_cpf[:3, 3]
        b = world_from_cpf[:3, :3] @ p + a
        ax[0].plot([a[0], b[0]], [a[1], b[1]], color="tab:red", lw=0.6)
    ax[0].set_aspect("equal")
    ax[0].set_title("device path from above, gaze rays every 0.5 s")
    ax[0].set_xlabel("x (m)")
    ax[0].set_ylabel("y (m)")

    ts = (imu[:, 0] - imu[0, 0]) * 1e-9
    first = ts <= 10.0
    for i, c in enumerate(["tab:red", "tab:green", "tab:blue"]):
        ax[1].plot(ts[first], imu[first, 1 + i], color=c, lw=0.5, label="xyz"[i])
        ax[2].plot(ts[first], imu[first, 4 + i], color=c, lw=0.5, label="xyz"[i])
    ax[1].set_title("imu-right accelerometer (raw, m/s²)")
    ax[2].set_title("imu-right gyroscope (raw, rad/s)")
    for a in ax[1:3]:
        a.set_xlabel("time (s)")
        a.legend(loc="upper right")

    yaw = np.array([g.yaw for g in gaze])
    pitch = np.array([g.pitch for g in gaze])
    d = np.stack([np.tan(yaw), np.tan(pitch), np.ones_like(yaw)], axis=1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    ecc = np.degrees(np.arccos(np.clip(d[:, 2], -1, 1)))
    tg = np.array([g.tracking_timestamp.total_seconds() for g in gaze])
    # Gaze in the world (head-free eye tracking): a fixation holds the world direction still.
    rot = np.array([
        (traj[min(int(round(t * 1000)), len(traj) - 1)].transform_world_device.to_matrix()
         @ t_device_cpf)[:3, :3] for t in tg])
    dw = np.einsum("nij,nj->ni", rot, d)
    speed = np.degrees(np.arccos(np.clip(np.sum(dw[1:] * dw[:-1], axis=1), -1, 1))) / np.diff(tg)
    slow = np.concatenate([[True], speed < 30.0])
    durations, run = [], 0
    for s in slow:
        if s:
            run += 1
        elif run:
            durations.append(run / 200.0)
            run = 0
    durations = np.array([x for x in durations if x >= 0.06])
    ax[3].hist(ecc, bins=31, range=(0, 31), density=True, color="tab:blue", alpha=0.7)
    ax[3].set_title("gaze angle to the head's forward direction")
    ax[3].set_xlabel("degrees (the eyes stay within 30)")
    ax[4].hist(durations, bins=30, range=(0, 1.5), density=True, alpha=0.6, color="tab:orange",
               label=f"found by I-VT (30 deg/s, gaze in the world): median {np.median(durations):.2f}, mean {durations.mean():.2f}")
    x = np.linspace(0.01, 1.5, 200)
    pdf = np.exp(-(np.log(x / 0.28)) ** 2 / (2 * 0.45**2)) / (x * 0.45 * np.sqrt(2 * np.pi))
    ax[4].plot(x, pdf, color="k", lw=1, label="model: log-normal, median 0.28 s")
    ax[4].axvline(0.33, color="k", ls="--", lw=1, label="Rayner 1998: mean 0.33 s")
    ax[4].set_title("fixation durations")
    ax[4].set_xlabel("seconds")
    ax[4].legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    with outputs.writing(out, replace) as tmp:
        fig.savefig(tmp, dpi=80, format=outputs.format_of(out))
    print(f"wrote {out}: {len(durations)} fixations by I-VT, median {np.median(durations):.3f} s, "
          f"mean {durations.mean():.3f} s; gaze angle median {np.median(ecc):.1f} deg, "
          f"90th percentile {np.percentile(ecc, 90):.1f} deg")


if __name__ == "__main__":
    args, replace = arguments.switch(sys.argv[1:], "--replace")
    if len(args) != 4:
        sys.exit("usage: plot_aria_streams.py TAKE ARIA WEARER OUT [--replace]")
    main(*args, replace=replace)
