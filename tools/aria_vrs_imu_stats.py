#!/usr/bin/env python3
"""Specific force and angular rate of a real Aria recording's IMU streams (docs/MOTION.md, "Head
motion": the sanity check beside the IMU computed from a head trajectory). Reads a VRS file with
projectaria-tools (PyPI) and prints, per IMU, its samples, span and the median / p99 / max of
|accelerometer| (m/s²) and |gyroscope| (rad/s), as the device measured them (no calibration
undone).

    pip install projectaria-tools numpy
    python3 tools/aria_vrs_imu_stats.py recording.vrs

projectaria_tools' repository holds a real recording:
data/gen1/aria_everyday_activities_test_data/recording.vrs (0.4 s).
"""
import sys

import numpy as np
from projectaria_tools.core import data_provider


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    provider = data_provider.create_vrs_data_provider(sys.argv[1])
    if provider is None:
        sys.exit(f"{sys.argv[1]}: not a VRS file projectaria-tools can open")
    for label in ("imu-left", "imu-right"):
        stream = provider.get_stream_id_from_label(label)
        if stream is None:
            print(f"{label}: not in the recording")
            continue
        n = provider.get_num_data(stream)
        data = [provider.get_imu_data_by_index(stream, i) for i in range(n)]
        force = np.linalg.norm([d.accel_msec2 for d in data], axis=1)
        rate = np.linalg.norm([d.gyro_radsec for d in data], axis=1)
        span = (data[-1].capture_timestamp_ns - data[0].capture_timestamp_ns) * 1e-9
        print(
            f"{label}: {n} samples over {span:.3f} s; |specific force| median {np.median(force):.2f}, "
            f"p99 {np.percentile(force, 99):.2f}, max {force.max():.2f} m/s²; |angular rate| median "
            f"{np.median(rate):.2f}, p99 {np.percentile(rate, 99):.2f}, max {rate.max():.2f} rad/s"
        )


if __name__ == "__main__":
    main()
