//! What an IMU on the head measures: the true specific force and angular rate of its frame,
//! sampled from the head's trajectory spline at the IMU's rate, then (when asked) a device's
//! errors: white noise, a bias random walk, a turn-on bias, the device's own scale and
//! misalignment (its calibration's rectification matrix and bias, which the written
//! calibration carries so readers can undo them), and saturation.
//!
//! Model, per sensor (accelerometer or gyroscope) and axis, at sample `k` of period `Δt`:
//! `true` = specific force `Rᵀ(a − g)` (g = (0, 0, −9.81) m/s², world z up) or body rate `ω`;
//! `rectified = true + b_on + b_k + σ_w / √Δt · n_k`, `b_{k+1} = b_k + σ_b √Δt · m_k`
//! (`n`, `m` standard normal, seeded); `raw = clamp(M · rectified + b_cal, ±saturation)` with
//! `M`, `b_cal` the rig's calibration of that IMU (projectaria-tools: `rectified = M⁻¹ (raw −
//! b_cal)`). With errors off, `raw = true` and the written calibration is the identity.

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

use crate::math::pose_spline::{PoseSample, PoseSpline};
use crate::math::random::standard_normal;
use crate::math::{Affine3, Real, Vec3};
use crate::rig::ImuCalibration;

/// Gravity in the world (m/s², z up), as MPS writes it.
pub(crate) const GRAVITY_WORLD: Vec3 = Vec3::new(0.0, 0.0, -9.81);
/// One g in m/s², the unit the Aria noise tables use.
const G: Real = 9.81;
const DEG: Real = std::f64::consts::PI / 180.0;

/// The error model of one sensor (three axes alike).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorErrors {
    /// White noise density (unit/√Hz: m/s²/√Hz or rad/s/√Hz).
    pub noise_density: Real,
    /// Bias random walk density (unit·√Hz: m/s³/√Hz or rad/s²/√Hz).
    pub bias_random_walk: Real,
    /// Standard deviation of the bias drawn when the device starts (m/s² or rad/s).
    pub turn_on_bias_sigma: Real,
    /// Largest magnitude measured on an axis (m/s² or rad/s).
    pub saturation: Real,
}

/// The error model of one IMU.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImuErrors {
    pub accelerometer: SensorErrors,
    pub gyroscope: SensorErrors,
}

impl ImuErrors {
    /// Project Aria gen1's published figures for the IMU labelled `label` (projectaria-tools
    /// docs, "IMU noise model": white noise from 24 h Allan variance; saturation from the
    /// sensor measurement model page). Labels other than `imu-left` get `imu-right`'s. No
    /// bias random walk is published: it is set so that the bias drifts by the published bias
    /// instability over 100 s (`σ_b = instability / √100 s`); no turn-on bias is published
    /// either (0: the device calibration's bias stands for it).
    pub fn aria_gen1(label: &str) -> Self {
        let (accel_noise_g, accel_instability_g, accel_sat_g, gyro_noise_dps, gyro_instability_dps) =
            if label == "imu-left" {
                (0.9e-4, 2.8e-5, 8.0, 5e-3, 1e-3)
            } else {
                (0.8e-4, 3.5e-5, 16.0, 1e-2, 1.3e-3)
            };
        let per_100_s = 1.0 / 100.0_f64.sqrt();
        ImuErrors {
            accelerometer: SensorErrors {
                noise_density: accel_noise_g * G,
                bias_random_walk: accel_instability_g * G * per_100_s,
                turn_on_bias_sigma: 0.0,
                saturation: accel_sat_g * G,
            },
            gyroscope: SensorErrors {
                noise_density: gyro_noise_dps * DEG,
                bias_random_walk: gyro_instability_dps * DEG * per_100_s,
                turn_on_bias_sigma: 0.0,
                saturation: 2000.0 * DEG,
            },
        }
    }

    /// Why these errors cannot be simulated, naming the field, or `None`.
    pub(crate) fn problem(&self) -> Option<String> {
        for (sensor, e) in [
            ("accelerometer", &self.accelerometer),
            ("gyroscope", &self.gyroscope),
        ] {
            for (key, v) in [
                ("noise_density", e.noise_density),
                ("bias_random_walk", e.bias_random_walk),
                ("turn_on_bias_sigma", e.turn_on_bias_sigma),
            ] {
                if !(v.is_finite() && v >= 0.0) {
                    return Some(format!(
                        "{sensor}.{key} = {v}: expected a finite number ≥ 0"
                    ));
                }
            }
            if !(e.saturation.is_finite() && e.saturation > 0.0) {
                return Some(format!(
                    "{sensor}.saturation = {}: expected a finite number > 0",
                    e.saturation
                ));
            }
        }
        None
    }
}

/// One IMU sample: time on the device clock and what the sensor reports (raw, as the device
/// would record it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ImuSample {
    pub timestamp_ns: i64,
    /// Specific force (m/s²), in the IMU frame.
    pub accel: Vec3,
    /// Angular rate (rad/s), in the IMU frame.
    pub gyro: Vec3,
}

/// The true specific force and angular rate of a frame in the state `s` (both in that frame).
pub(crate) fn true_measurement(s: &PoseSample) -> (Vec3, Vec3) {
    let frame_from_world = s.world_from_body.matrix3.transpose();
    (
        frame_from_world * (s.acceleration_world - GRAVITY_WORLD),
        s.angular_velocity_body,
    )
}

/// Sample times of a stream at `rate_hz` over `[0, duration_s]`, in whole nanoseconds.
pub(crate) fn sample_times_ns(rate_hz: Real, duration_s: Real) -> Vec<i64> {
    let count = (duration_s * rate_hz + 1e-9).floor() as i64 + 1;
    (0..count)
        .map(|k| (k as Real * 1e9 / rate_hz).round() as i64)
        .collect()
}

/// The IMU at `head_from_imu` on a head moving along `spline`, sampled at `rate_hz`; with
/// `errors`, the device's errors drawn from `seed` and its `calibration` applied.
pub(crate) fn simulate_imu(
    spline: &PoseSpline,
    head_from_imu: Affine3,
    rate_hz: Real,
    errors: Option<(&ImuErrors, &ImuCalibration, u64)>,
) -> Vec<ImuSample> {
    simulate_imu_with_biases(spline, head_from_imu, rate_hz, errors)
        .into_iter()
        .map(|r| r.sample)
        .collect()
}

/// One IMU sample and the sensor's biases when it was taken (`b_on + b_k` of the model, in the
/// rectified units: m/s² and rad/s in the IMU frame; 0 without errors), what a ground truth
/// of the IMU's state holds beside its pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ImuReading {
    pub sample: ImuSample,
    pub accel_bias: Vec3,
    pub gyro_bias: Vec3,
}

/// [`simulate_imu`], each sample with the biases it was taken with.
pub(crate) fn simulate_imu_with_biases(
    spline: &PoseSpline,
    head_from_imu: Affine3,
    rate_hz: Real,
    errors: Option<(&ImuErrors, &ImuCalibration, u64)>,
) -> Vec<ImuReading> {
    let times = sample_times_ns(rate_hz, spline.duration_s());
    let dt = 1.0 / rate_hz;
    let mut readings: Vec<ImuReading> = times
        .iter()
        .map(|&ns| {
            let s = spline.sample(ns as Real * 1e-9).attached(head_from_imu);
            let (accel, gyro) = true_measurement(&s);
            ImuReading {
                sample: ImuSample {
                    timestamp_ns: ns,
                    accel,
                    gyro,
                },
                accel_bias: Vec3::ZERO,
                gyro_bias: Vec3::ZERO,
            }
        })
        .collect();
    let Some((e, cal, seed)) = errors else {
        return readings;
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let normal3 = |rng: &mut ChaCha8Rng| {
        Vec3::new(
            standard_normal(rng),
            standard_normal(rng),
            standard_normal(rng),
        )
    };
    let mut accel_bias = normal3(&mut rng) * e.accelerometer.turn_on_bias_sigma;
    let mut gyro_bias = normal3(&mut rng) * e.gyroscope.turn_on_bias_sigma;
    let white = |s: &SensorErrors| s.noise_density / dt.sqrt();
    let walk = |s: &SensorErrors| s.bias_random_walk * dt.sqrt();
    let clamp = |v: Vec3, limit: Real| v.clamp(Vec3::splat(-limit), Vec3::splat(limit));
    for reading in &mut readings {
        let sample = &mut reading.sample;
        let accel = sample.accel + accel_bias + normal3(&mut rng) * white(&e.accelerometer);
        let gyro = sample.gyro + gyro_bias + normal3(&mut rng) * white(&e.gyroscope);
        sample.accel = clamp(
            cal.accel_rectification * accel + cal.accel_bias,
            e.accelerometer.saturation,
        );
        sample.gyro = clamp(
            cal.gyro_rectification * gyro + cal.gyro_bias,
            e.gyroscope.saturation,
        );
        reading.accel_bias = accel_bias;
        reading.gyro_bias = gyro_bias;
        accel_bias += normal3(&mut rng) * walk(&e.accelerometer);
        gyro_bias += normal3(&mut rng) * walk(&e.gyroscope);
    }
    readings
}

/// Allan deviation of `values` sampled every `dt` seconds at cluster size `m` samples
/// (non-overlapping clusters): `√(½ ⟨(ȳ_{k+1} − ȳ_k)²⟩)`.
#[cfg(test)]
pub(crate) fn allan_deviation(values: &[Real], m: usize) -> Real {
    let means: Vec<Real> = values
        .chunks_exact(m.max(1))
        .map(|c| c.iter().sum::<Real>() / c.len() as Real)
        .collect();
    if means.len() < 2 {
        return Real::NAN;
    }
    let sum: Real = means.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum();
    (0.5 * sum / (means.len() - 1) as Real).sqrt()
}
