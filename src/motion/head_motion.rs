//! How a head moves, in the numbers a real head is held to: linear acceleration (on the frames
//! where two motion primitives join, against the frames inside them), angular speed, side-to-side
//! yaw sway, vertical bob, step frequency, and what an IMU on it reads. One definition for
//! every source, so a take's wearer, the CMU mocap heads the motion model learnt from and a real
//! Aria wearer's MPS trajectory are compared like with like (`egogen motion head-stats`,
//! docs/MOTION.md "Head motion"). Also reads an MPS closed-loop trajectory CSV and resamples any
//! timed pose track to the statistics' rate.
//!
//! Definitions, on a track of head poses at [`STATS_RATE_HZ`] in a z-up world, the head frame's
//! z axis its viewing direction (egogen's CPF):
//! - linear acceleration of frame `f`: `|x(f+1) − 2 x(f) + x(f−1)| · rate²`;
//! - join frames: the two frames whose central difference spans the join of two primitives
//!   (the last of one, the first of the next: frames `f` with `(f − 2) mod 18` = 17 or 0), the
//!   same frames on a real track, where nothing joins;
//! - angular speed of frame `f`: the angle of `R(f)ᵀ R(f+1)` · rate;
//! - yaw sway: the heading of the viewing direction's horizontal part, less its centred
//!   1 s moving average, RMS; vertical bob: the height less its centred 1 s moving average, RMS;
//! - step frequency: the peak of the bob's autocorrelation between 0.3 and 0.8 s lag;
//! - path-ahead angle: between the viewing direction's heading and the direction to the point
//!   of the head's own path 2 m on (where the head gets within 4 s);
//! - walking frames: the head's horizontal speed, averaged over ±0.25 s, at least
//!   [`WALKING_SPEED_M_S`], outside activities (a take's sitting down, seated, standing up,
//!   picking up, standing and looking: its `summary.json`'s activity segments). Sway, bob, step frequency, angular speed and the IMU are over
//!   walking frames; acceleration is given over every frame and over walking frames.

use std::path::Path;

use serde::Serialize;

use super::primitive::{NEW_FRAMES, SEED_FRAMES};
use crate::math::{matrix_to_axis_angle, wrap_rad, Affine3, Mat3, Quantiles, Real, Vec3};

/// The rate every track is measured at (the motion model's).
pub(crate) const STATS_RATE_HZ: Real = 40.0;
/// Horizontal head speed from which a frame counts as walking (m/s).
pub(crate) const WALKING_SPEED_M_S: Real = 0.5;
/// Window of the moving averages sway and bob are measured against (s).
const DETREND_S: Real = 1.0;
/// How far along its path the head's heading is compared with where the walk goes (m).
pub(crate) const PATH_AHEAD_M: Real = 2.0;
/// The path ahead counts only when the head gets there within this time (s).
pub(crate) const PATH_AHEAD_MAX_S: Real = 4.0;

/// A head's poses at a fixed rate (`world_from_head`, world z up, head z forward).
#[derive(Debug, Clone)]
pub(crate) struct HeadTrack {
    pub rate_hz: Real,
    pub world_from_head: Vec<Affine3>,
}

/// Specific force and angular rate magnitudes of an IMU on the head, in time order.
#[derive(Debug, Clone, Default)]
pub(crate) struct ImuTrace {
    pub rate_hz: Real,
    /// |specific force| (m/s²) per sample.
    pub specific_force: Vec<Real>,
    /// |angular rate| (rad/s) per sample.
    pub gyro: Vec<Real>,
}

/// Linear acceleration on the frames where primitives join against the frames inside them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct JoinAcceleration {
    /// Every frame (m/s²).
    pub all: Quantiles,
    /// Walking frames (m/s²).
    pub walking: Quantiles,
    /// Join frames (m/s²).
    pub join: Quantiles,
    /// Frames inside primitives (m/s²).
    pub inside: Quantiles,
    /// Join-frame median over inside median.
    pub join_ratio_median: Real,
    /// Join-frame p95 over inside p95.
    pub join_ratio_p95: Real,
}

/// What an IMU on the head reads while walking.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct ImuStats {
    /// |specific force| (m/s²).
    pub specific_force: Quantiles,
    /// |angular rate| (rad/s).
    pub gyro: Quantiles,
}

/// The statistics of one head track (and, where the source has a body, its pelvis).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct HeadMotionStats {
    pub label: String,
    pub duration_s: Real,
    pub walking_s: Real,
    /// Head linear acceleration.
    pub head_acceleration: JoinAcceleration,
    /// Pelvis linear acceleration, where the source has a pelvis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pelvis_acceleration: Option<JoinAcceleration>,
    /// Head angular speed while walking (rad/s).
    pub angular_speed: Quantiles,
    pub yaw_sway_rms_deg: Real,
    /// While walking, the angle between the viewing direction's heading and the direction to
    /// the point of the head's own path [`PATH_AHEAD_M`] on (reached within
    /// [`PATH_AHEAD_MAX_S`]), degrees: how far the eyes turn from the head to look where the
    /// walk goes.
    pub path_ahead_deg: Quantiles,
    pub bob_rms_mm: Real,
    /// NaN where the track walks too little to tell.
    pub step_hz: Real,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub imu: Option<ImuStats>,
}

/// Whether frame `f`'s central difference spans the join of two primitives.
pub(crate) fn is_join_frame(f: usize) -> bool {
    f + 1 >= SEED_FRAMES && {
        let k = (f + 1 - SEED_FRAMES) % NEW_FRAMES;
        k == 0 || k == 1
    }
}

fn accelerations(points: &[Vec3], rate_hz: Real) -> Vec<Real> {
    (0..points.len())
        .map(|f| {
            if f == 0 || f + 1 >= points.len() {
                Real::NAN
            } else {
                (points[f + 1] - 2.0 * points[f] + points[f - 1]).length() * rate_hz * rate_hz
            }
        })
        .collect()
}

fn join_acceleration(points: &[Vec3], rate_hz: Real, walking: &[bool]) -> JoinAcceleration {
    let acc = accelerations(points, rate_hz);
    let pick = |keep: &dyn Fn(usize) -> bool| {
        Quantiles::of(
            acc.iter()
                .enumerate()
                .filter(|(f, _)| keep(*f))
                .map(|(_, a)| *a),
        )
    };
    let join = pick(&|f| is_join_frame(f));
    let inside = pick(&|f| !is_join_frame(f));
    JoinAcceleration {
        all: pick(&|_| true),
        walking: pick(&|f| walking[f]),
        join,
        inside,
        join_ratio_median: join.p50 / inside.p50,
        join_ratio_p95: join.p95 / inside.p95,
    }
}

/// Centred moving average over `half` frames either side (fewer at the ends).
fn moving_average(v: &[Real], half: usize) -> Vec<Real> {
    let mut prefix = Vec::with_capacity(v.len() + 1);
    prefix.push(0.0);
    for x in v {
        prefix.push(prefix[prefix.len() - 1] + x);
    }
    (0..v.len())
        .map(|f| {
            let a = f.saturating_sub(half);
            let b = (f + half + 1).min(v.len());
            (prefix[b] - prefix[a]) / (b - a) as Real
        })
        .collect()
}

/// Which frames walk: horizontal speed averaged over ±0.25 s at least [`WALKING_SPEED_M_S`].
pub(crate) fn walking_frames(points: &[Vec3], rate_hz: Real) -> Vec<bool> {
    let n = points.len();
    if n < 2 {
        return vec![false; n];
    }
    let speed: Vec<Real> = (0..n)
        .map(|f| {
            let (a, b) = (f.saturating_sub(1), (f + 1).min(n - 1));
            let d = points[b] - points[a];
            d.truncate().length() * rate_hz / (b - a) as Real
        })
        .collect();
    let half = (0.25 * rate_hz).round() as usize;
    moving_average(&speed, half)
        .into_iter()
        .map(|s| s >= WALKING_SPEED_M_S)
        .collect()
}

fn rms_over(v: &[Real], keep: &[bool]) -> Real {
    let (sum, n) = v
        .iter()
        .zip(keep)
        .filter(|(x, k)| **k && x.is_finite())
        .fold((0.0, 0usize), |(s, n), (x, _)| (s + x * x, n + 1));
    (sum / n as Real).sqrt()
}

/// Frames whose whole detrending window lies inside the track and walks.
fn detrend_mask(walking: &[bool], half: usize) -> Vec<bool> {
    let n = walking.len();
    (0..n)
        .map(|f| f >= half && f + half < n && walking[f - half..=f + half].iter().all(|w| *w))
        .collect()
}

/// Step frequency (Hz) from the autocorrelation of `residual` over `keep`, its peak between
/// 0.3 and 0.8 s of lag refined by a parabola; NaN without 2 s of kept frames or a peak.
fn step_frequency(residual: &[Real], keep: &[bool], rate_hz: Real) -> Real {
    let x: Vec<Real> = residual
        .iter()
        .zip(keep)
        .map(|(r, k)| if *k { *r } else { 0.0 })
        .collect();
    if (keep.iter().filter(|k| **k).count() as Real) < 2.0 * rate_hz {
        return Real::NAN;
    }
    let lo = (0.3 * rate_hz).floor() as usize;
    let hi = (0.8 * rate_hz).ceil() as usize;
    let corr = |lag: usize| -> Real {
        (0..x.len().saturating_sub(lag))
            .map(|i| x[i] * x[i + lag])
            .sum()
    };
    let c: Vec<Real> = (lo - 1..=hi + 1).map(corr).collect();
    let best = (1..c.len() - 1)
        .filter(|&i| c[i] >= c[i - 1] && c[i] >= c[i + 1] && c[i] > 0.0)
        .max_by(|&a, &b| c[a].total_cmp(&c[b]));
    let Some(i) = best else {
        return Real::NAN;
    };
    let denom = c[i - 1] - 2.0 * c[i] + c[i + 1];
    let shift = if denom.abs() > 0.0 {
        0.5 * (c[i - 1] - c[i + 1]) / denom
    } else {
        0.0
    };
    let lag = (lo - 1 + i) as Real + shift.clamp(-0.5, 0.5);
    rate_hz / lag
}

/// The heading (radians, unwrapped along the track) of the viewing direction's horizontal part.
pub(crate) fn unwrapped_yaw(world_from_head: &[Affine3]) -> Vec<Real> {
    let mut out: Vec<Real> = Vec::with_capacity(world_from_head.len());
    for p in world_from_head {
        let z = p.matrix3.z_axis;
        let mut yaw = z.y.atan2(z.x);
        if let Some(&prev) = out.last() {
            let tau = std::f64::consts::TAU;
            yaw += ((prev - yaw) / tau).round() * tau;
        }
        out.push(yaw);
    }
    out
}

/// Per frame, the heading (rad) from the head to the point of its own path `ahead_m` on
/// (horizontal path length), where the head gets there within `max_frames` frames.
pub(crate) fn path_ahead_heading(
    points: &[Vec3],
    ahead_m: Real,
    max_frames: usize,
) -> Vec<Option<Real>> {
    let mut along = Vec::with_capacity(points.len());
    let mut s = 0.0;
    for (f, p) in points.iter().enumerate() {
        if f > 0 {
            s += (*p - points[f - 1]).truncate().length();
        }
        along.push(s);
    }
    let mut g = 0;
    (0..points.len())
        .map(|f| {
            g = g.max(f);
            while g < points.len() && along[g] - along[f] < ahead_m {
                g += 1;
            }
            (g < points.len() && g - f <= max_frames).then(|| {
                let d = (points[g] - points[f]).truncate();
                d.y.atan2(d.x)
            })
        })
        .collect()
}

/// The angle of the rotation from `a` to `b` (accurate near 0, where `acos` of the trace is not).
fn angle_between(a: Mat3, b: Mat3) -> Real {
    matrix_to_axis_angle(a.transpose() * b).length()
}

impl HeadMotionStats {
    /// Measures `head` (and `pelvis` positions at the same frames, where given; an `imu` trace
    /// of the same head, where given); frames `busy` marks (an activity: sitting down, picking
    /// up) never count as walking.
    pub(crate) fn measure(
        label: &str,
        head: &HeadTrack,
        pelvis: Option<&[Vec3]>,
        imu: Option<&ImuTrace>,
        busy: Option<&[bool]>,
    ) -> HeadMotionStats {
        let rate = head.rate_hz;
        let points: Vec<Vec3> = head.world_from_head.iter().map(|p| p.translation).collect();
        let n = points.len();
        let mut walking = walking_frames(&points, rate);
        if let Some(busy) = busy {
            for (w, b) in walking.iter_mut().zip(busy) {
                *w &= !b;
            }
        }
        let half = (0.5 * DETREND_S * rate).round() as usize;
        let kept = detrend_mask(&walking, half);
        let yaw = unwrapped_yaw(&head.world_from_head);
        let yaw_res: Vec<Real> = yaw
            .iter()
            .zip(moving_average(&yaw, half))
            .map(|(y, m)| y - m)
            .collect();
        let z: Vec<Real> = points.iter().map(|p| p.z).collect();
        let bob: Vec<Real> = z
            .iter()
            .zip(moving_average(&z, half))
            .map(|(y, m)| y - m)
            .collect();
        let angular_speed =
            Quantiles::of((0..n.saturating_sub(1)).filter(|&f| walking[f]).map(|f| {
                angle_between(
                    head.world_from_head[f].matrix3,
                    head.world_from_head[f + 1].matrix3,
                ) * rate
            }));
        let ahead = path_ahead_heading(
            &points,
            PATH_AHEAD_M,
            (PATH_AHEAD_MAX_S * rate).round() as usize,
        );
        let path_ahead_deg = Quantiles::of(
            (0..n)
                .filter(|&f| walking[f])
                .filter_map(|f| ahead[f].map(|a| wrap_rad(a - yaw[f]).abs().to_degrees())),
        );
        let imu = imu.map(|t| {
            let walking_at = |k: usize| {
                let f = ((k as Real / t.rate_hz) * rate).round() as usize;
                walking.get(f).copied().unwrap_or(false)
            };
            let pick = |v: &[Real]| {
                Quantiles::of(
                    v.iter()
                        .enumerate()
                        .filter(|(k, _)| walking_at(*k))
                        .map(|(_, x)| *x),
                )
            };
            ImuStats {
                specific_force: pick(&t.specific_force),
                gyro: pick(&t.gyro),
            }
        });
        HeadMotionStats {
            label: label.to_string(),
            duration_s: n.saturating_sub(1) as Real / rate,
            walking_s: walking.iter().filter(|w| **w).count() as Real / rate,
            head_acceleration: join_acceleration(&points, rate, &walking),
            pelvis_acceleration: pelvis.map(|p| join_acceleration(p, rate, &walking)),
            angular_speed,
            yaw_sway_rms_deg: rms_over(&yaw_res, &kept).to_degrees(),
            path_ahead_deg,
            bob_rms_mm: rms_over(&bob, &kept) * 1e3,
            step_hz: step_frequency(&bob, &kept, rate),
            imu,
        }
    }
}

/// Poses at `rate_hz` over the span of timed poses (`times_s` increasing): positions linearly
/// interpolated, rotations by slerp.
pub(crate) fn resample_poses(times_s: &[Real], poses: &[Affine3], rate_hz: Real) -> Vec<Affine3> {
    if times_s.is_empty() {
        return Vec::new();
    }
    let t0 = times_s[0];
    let span = times_s[times_s.len() - 1] - t0;
    let count = (span * rate_hz + 1e-9).floor() as usize + 1;
    let mut k = 0;
    (0..count)
        .map(|i| {
            let t = t0 + i as Real / rate_hz;
            while k + 2 < times_s.len() && times_s[k + 1] < t {
                k += 1;
            }
            let k1 = (k + 1).min(times_s.len() - 1);
            let dt = times_s[k1] - times_s[k];
            let u = if dt > 0.0 {
                ((t - times_s[k]) / dt).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (a, b) = (poses[k], poses[k1]);
            let qa = glam::DQuat::from_mat3(&a.matrix3);
            let qb = glam::DQuat::from_mat3(&b.matrix3);
            Affine3 {
                matrix3: Mat3::from_quat(qa.slerp(qb, u).normalize()),
                translation: a.translation.lerp(b.translation, u),
            }
        })
        .collect()
}

/// What went wrong reading an MPS trajectory.
#[derive(Debug, thiserror::Error)]
pub enum MpsTrajectoryError {
    #[error("reading {path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Format { path: String, message: String },
}

/// A projectaria-tools MPS closed-loop (or open-loop) trajectory CSV: times (s, from
/// `tracking_timestamp_us`) and `world_from_device` poses (`tx_world_device` … `qw_world_device`).
pub fn read_mps_trajectory(path: &Path) -> Result<(Vec<Real>, Vec<Affine3>), MpsTrajectoryError> {
    let shown = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| MpsTrajectoryError::Io {
        path: shown.clone(),
        source,
    })?;
    let bad = |message: String| MpsTrajectoryError::Format {
        path: shown.clone(),
        message,
    };
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .ok_or_else(|| bad("empty file; expected an MPS trajectory CSV header".into()))?
        .split(',')
        .map(str::trim)
        .collect();
    const COLUMNS: [&str; 8] = [
        "tracking_timestamp_us",
        "tx_world_device",
        "ty_world_device",
        "tz_world_device",
        "qx_world_device",
        "qy_world_device",
        "qz_world_device",
        "qw_world_device",
    ];
    let index: Vec<usize> = COLUMNS
        .iter()
        .map(|c| {
            header
                .iter()
                .position(|h| h == c)
                .ok_or_else(|| bad(format!("no column `{c}` in the header")))
        })
        .collect::<Result<_, _>>()?;
    let (mut times, mut poses) = (Vec::new(), Vec::new());
    for (i, line) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').collect();
        let mut v = [0.0; 8];
        for (slot, (&col, name)) in v.iter_mut().zip(index.iter().zip(COLUMNS)) {
            let field = fields.get(col).map(|s| s.trim()).unwrap_or("");
            *slot = field
                .parse::<Real>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    bad(format!(
                        "line {}: column `{name}`: expected a finite number, got {field:?}",
                        i + 2
                    ))
                })?;
        }
        let t = v[0] * 1e-6;
        if let Some(&prev) = times.last() {
            if t <= prev {
                return Err(bad(format!(
                    "line {}: `tracking_timestamp_us` does not increase",
                    i + 2
                )));
            }
        }
        let q = glam::DQuat::from_xyzw(v[4], v[5], v[6], v[7]);
        if (q.length() - 1.0).abs() > 1e-3 {
            return Err(bad(format!(
                "line {}: the quaternion has norm {:.6}; expected a unit quaternion",
                i + 2,
                q.length()
            )));
        }
        times.push(t);
        poses.push(Affine3 {
            matrix3: Mat3::from_quat(q.normalize()),
            translation: Vec3::new(v[1], v[2], v[3]),
        });
    }
    if times.len() < 2 {
        return Err(bad("fewer than two poses".into()));
    }
    Ok((times, poses))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A head walking at 1.2 m/s along +x, bobbing `bob_m` at 2 Hz and yawing `sway_rad` at
    /// 1 Hz, at 40 Hz for 10 s.
    fn walker(bob_m: Real, sway_rad: Real) -> HeadTrack {
        let poses = (0..400)
            .map(|f| {
                let t = f as Real / 40.0;
                let yaw = sway_rad * (2.0 * PI * t).sin();
                // Head z (forward) along the heading, y up.
                let fwd = Vec3::new(yaw.cos(), yaw.sin(), 0.0);
                let up = Vec3::Z;
                Affine3 {
                    matrix3: Mat3::from_cols(up.cross(fwd), up, fwd),
                    translation: Vec3::new(1.2 * t, 0.0, 1.6 + bob_m * (4.0 * PI * t).sin()),
                }
            })
            .collect();
        HeadTrack {
            rate_hz: 40.0,
            world_from_head: poses,
        }
    }

    #[test]
    fn known_sway_bob_and_step_frequency_are_measured() {
        let s = HeadMotionStats::measure("w", &walker(0.015, 0.05), None, None, None);
        // A sine's RMS is its amplitude / √2 (the 1 s average of a 1 Hz or 2 Hz sine is 0).
        assert!((s.bob_rms_mm - 15.0 / 2f64.sqrt()).abs() < 0.3, "{s:?}");
        assert!(
            (s.yaw_sway_rms_deg - 0.05f64.to_degrees() / 2f64.sqrt()).abs() < 0.05,
            "{s:?}"
        );
        assert!((s.step_hz - 2.0).abs() < 0.05, "{s:?}");
        assert!((s.walking_s - 10.0).abs() < 0.1);
        // Bob acceleration peaks at 0.015 (4π)² = 2.37 m/s².
        assert!((s.head_acceleration.all.max - 0.015 * (4.0 * PI).powi(2)).abs() < 0.05);
        assert!(
            (s.head_acceleration.join_ratio_median - 1.0).abs() < 0.3,
            "{s:?}"
        );
    }

    #[test]
    fn a_velocity_jump_at_every_join_shows_on_the_join_frames() {
        let mut t = walker(0.0, 0.0);
        // Shift everything after each join back by 1 cm: a velocity jump at the join.
        let mut shift = 0.0;
        for f in 0..t.world_from_head.len() {
            if f >= SEED_FRAMES && (f - SEED_FRAMES).is_multiple_of(NEW_FRAMES) {
                shift += 0.01;
            }
            t.world_from_head[f].translation.x -= shift;
        }
        let s = HeadMotionStats::measure("w", &t, None, None, None);
        assert!((s.head_acceleration.join.p50 - 0.01 * 1600.0).abs() < 1e-6);
        assert!(s.head_acceleration.inside.p95 < 1e-6);
    }

    #[test]
    fn join_frames_are_the_two_either_side_of_each_join() {
        let joins: Vec<usize> = (0..60).filter(|&f| is_join_frame(f)).collect();
        assert_eq!(joins, vec![1, 2, 19, 20, 37, 38, 55, 56]);
    }

    #[test]
    fn the_path_ahead_is_found_by_its_length_and_only_within_time() {
        // 1 m a frame along +x, then along +y from frame 5.
        let points: Vec<Vec3> = (0..10)
            .map(|f| {
                if f <= 5 {
                    Vec3::new(f as Real, 0.0, 1.6)
                } else {
                    Vec3::new(5.0, (f - 5) as Real, 1.6)
                }
            })
            .collect();
        let ahead = path_ahead_heading(&points, 3.0, 10);
        assert_eq!(ahead[0], Some(0.0));
        // From frame 4 the point 3 m on is (5, 2).
        assert!((ahead[4].unwrap() - 2f64.atan2(1.0)).abs() < 1e-12);
        assert_eq!(ahead[7], None);
        assert_eq!(path_ahead_heading(&points, 3.0, 2)[0], None);
        for a in [-7.0, -PI, -1.0, 0.0, PI, 4.0, 100.0] {
            let w = wrap_rad(a);
            assert!(w > -PI - 1e-12 && w <= PI + 1e-12, "{a} → {w}");
            assert!(
                ((a - w) / std::f64::consts::TAU).fract().abs() < 1e-9
                    || ((a - w) / std::f64::consts::TAU).fract().abs() > 1.0 - 1e-9
            );
        }
    }

    #[test]
    fn resampling_keeps_the_poses_at_their_times() {
        let t = walker(0.01, 0.1);
        let times: Vec<Real> = (0..400).map(|f| f as Real / 40.0).collect();
        let again = resample_poses(&times, &t.world_from_head, 40.0);
        assert_eq!(again.len(), 400);
        for (a, b) in again.iter().zip(&t.world_from_head) {
            assert!((a.translation - b.translation).length() < 1e-12);
            assert!(angle_between(a.matrix3, b.matrix3) < 1e-7);
        }
    }
}
