//! An optional depth-sensor noise model, applied in Rust to a frame's exact planar depth; the
//! result is stored beside it as `depth_noisy.Z` (the exact `depth.Z` stays).
//!
//! Per pixel with a surface at planar depth `z` (m), seen at incidence angle `θ` (between the
//! surface normal and the viewing ray):
//! ```text
//! σ(z, θ) = a + b·(z − c)² + d · θ² / (√z · (π/2 − θ)²)
//! z_noisy = quantise(z + σ(z, θ)·N(0, 1))
//! ```
//! and `z_noisy = 0` (no measurement, as for background) where `θ > max_incidence`, `z` is
//! outside `[min_range_m, max_range_m]`, or the noisy value is not positive. The axial model is
//! Nguyen, Izadi & Lovell, "Modeling Kinect Sensor Noise for Improved 3D Reconstruction and
//! Tracking", 3DIMPVT 2012 (a = 0.0012 m, b = 0.0019 m⁻¹, c = 0.4 m, d = 0.0001 m^1.5, fitted to a
//! Kinect v1); the defaults are those numbers, i.e. estimates for any other sensor.
//!
//! Draws: one standard normal per pixel in raster order from ChaCha8 seeded with
//! SHA-256(seed, camera name, frame), so a frame's noise depends only on those three.

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use sha2::{Digest, Sha256};

use crate::math::random::standard_normal;
use crate::math::{Real, Vec3};

/// The model's parameters (see the module docs); `Default` is Nguyen et al.'s Kinect fit with
/// egogen's estimated limits.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DepthNoise {
    /// `a`: noise floor (m).
    pub sigma_base_m: Real,
    /// `b`: growth with distance (m⁻¹).
    pub sigma_quadratic_per_m: Real,
    /// `c`: distance of least noise (m).
    pub sigma_offset_m: Real,
    /// `d`: growth towards grazing incidence (m^1.5).
    pub sigma_grazing: Real,
    /// Larger incidence angles give no measurement (degrees, at most 90).
    pub max_incidence_deg: Real,
    pub min_range_m: Real,
    pub max_range_m: Real,
    /// Output step (m); 0 = none.
    pub quantisation_m: Real,
}

impl Default for DepthNoise {
    fn default() -> Self {
        Self {
            sigma_base_m: 0.0012,
            sigma_quadratic_per_m: 0.0019,
            sigma_offset_m: 0.4,
            sigma_grazing: 0.0001,
            max_incidence_deg: 75.0,
            min_range_m: 0.4,
            max_range_m: 4.0,
            quantisation_m: 0.001,
        }
    }
}

impl DepthNoise {
    /// A model that changes nothing: no noise, no limits, no quantisation.
    #[cfg(test)]
    pub(crate) fn none() -> Self {
        Self {
            sigma_base_m: 0.0,
            sigma_quadratic_per_m: 0.0,
            sigma_offset_m: 0.0,
            sigma_grazing: 0.0,
            max_incidence_deg: 90.0,
            min_range_m: 0.0,
            max_range_m: Real::INFINITY,
            quantisation_m: 0.0,
        }
    }

    /// The parameter that cannot work, named as the config spells it, with what is expected.
    pub(crate) fn check(&self) -> Result<(), (&'static str, String)> {
        let non_negative = [
            ("sigma_base_m", self.sigma_base_m),
            ("sigma_quadratic_per_m", self.sigma_quadratic_per_m),
            ("sigma_offset_m", self.sigma_offset_m),
            ("sigma_grazing", self.sigma_grazing),
            ("min_range_m", self.min_range_m),
            ("quantisation_m", self.quantisation_m),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err((name, format!("expected a finite value ≥ 0, found {v}")));
            }
        }
        if !(self.max_incidence_deg > 0.0 && self.max_incidence_deg <= 90.0) {
            return Err((
                "max_incidence_deg",
                format!(
                    "expected an angle in (0, 90] degrees, found {}",
                    self.max_incidence_deg
                ),
            ));
        }
        if !(self.max_range_m > self.min_range_m) {
            return Err((
                "max_range_m",
                format!(
                    "expected more than min_range_m ({} m), found {}",
                    self.min_range_m, self.max_range_m
                ),
            ));
        }
        // Each parameter finite is not enough: σ itself must be, wherever depth is measured.
        let far = self.max_range_m.min(1e4);
        let steepest = self.max_incidence_deg.to_radians();
        for (z, theta) in [(far, steepest), (self.min_range_m.max(1e-3), steepest)] {
            let sigma = self.sigma_m(z, theta);
            if !(sigma.is_finite() && sigma * 8.0 < f32::MAX as Real) {
                return Err((
                    "sigma_base_m",
                    format!(
                        "expected parameters whose σ is finite at every measured depth: σ at \
                         {z} m, {:.1}° is {sigma} (sigma_base_m, sigma_quadratic_per_m, \
                         sigma_offset_m, sigma_grazing together)",
                        theta.to_degrees()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// `σ(z, θ)` in metres.
    pub fn sigma_m(&self, z_m: Real, incidence_rad: Real) -> Real {
        let mut sigma =
            self.sigma_base_m + self.sigma_quadratic_per_m * (z_m - self.sigma_offset_m).powi(2);
        if self.sigma_grazing > 0.0 {
            let t = incidence_rad.min(std::f64::consts::FRAC_PI_2 - 1e-9);
            sigma += self.sigma_grazing * t * t
                / (z_m.sqrt() * (std::f64::consts::FRAC_PI_2 - t).powi(2));
        }
        sigma
    }

    /// The noisy depth of a frame: `depth` planar (m, 0 = no surface), `normal` unit normals
    /// and `ray` unit viewing directions (both camera frame) per pixel.
    pub(crate) fn apply(
        &self,
        depth: &[f32],
        normal: &[[f32; 3]],
        ray: impl Fn(usize) -> Vec3,
        seed: NoiseSeed<'_>,
    ) -> Vec<f32> {
        let mut rng = seed.rng();
        let max_incidence = self.max_incidence_deg.to_radians();
        (0..depth.len())
            .map(|i| {
                let draw = standard_normal(&mut rng);
                let z = depth[i] as Real;
                if z <= 0.0 || z < self.min_range_m || z > self.max_range_m {
                    return 0.0;
                }
                let n = Vec3::new(
                    normal[i][0] as Real,
                    normal[i][1] as Real,
                    normal[i][2] as Real,
                );
                let cos = n.dot(ray(i)).abs().min(1.0);
                let incidence = cos.acos();
                if incidence > max_incidence {
                    return 0.0;
                }
                let sigma = self.sigma_m(z, incidence);
                if sigma == 0.0 && self.quantisation_m == 0.0 {
                    return depth[i];
                }
                let mut noisy = z + sigma * draw;
                if self.quantisation_m > 0.0 {
                    noisy = (noisy / self.quantisation_m).round() * self.quantisation_m;
                }
                if noisy > 0.0 {
                    noisy as f32
                } else {
                    0.0
                }
            })
            .collect()
    }
}

/// What a frame's noise is drawn from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct NoiseSeed<'a> {
    pub seed: u64,
    pub camera: &'a str,
    pub frame: u32,
}

impl NoiseSeed<'_> {
    fn rng(&self) -> ChaCha8Rng {
        let mut h = Sha256::new();
        h.update(b"egogen depth noise\0");
        h.update(self.seed.to_le_bytes());
        h.update(self.camera.as_bytes());
        h.update([0]);
        h.update(self.frame.to_le_bytes());
        ChaCha8Rng::from_seed(h.finalize().into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const SEED: NoiseSeed<'static> = NoiseSeed {
        seed: 7,
        camera: "depth",
        frame: 3,
    };

    /// A fronto-parallel plane at `z_m` seen by a 640×480 pinhole (f = 500 px): depth, normals
    /// facing the camera, viewing rays.
    fn plane(z_m: f32) -> (Vec<f32>, Vec<[f32; 3]>, impl Fn(usize) -> Vec3) {
        let (w, h) = (640usize, 480usize);
        let ray = move |i: usize| {
            let (x, y) = ((i % w) as Real - 319.5, (i / w) as Real - 239.5);
            Vec3::new(x / 500.0, y / 500.0, 1.0).normalize()
        };
        (vec![z_m; w * h], vec![[0.0, 0.0, -1.0]; w * h], ray)
    }

    #[test]
    fn noise_statistics_follow_sigma_of_z_on_a_plane() {
        // Quantisation and limits off, so the draws are z + σ·N(0, 1) exactly.
        let model = DepthNoise {
            quantisation_m: 0.0,
            max_incidence_deg: 90.0,
            min_range_m: 0.0,
            max_range_m: 100.0,
            ..DepthNoise::default()
        };
        for z in [0.8f32, 2.0, 3.5] {
            let (depth, normal, ray) = plane(z);
            let noisy = model.apply(&depth, &normal, &ray, SEED);
            let n = noisy.len() as Real;
            let mean = noisy.iter().map(|&v| v as Real - z as Real).sum::<Real>() / n;
            let std = (noisy
                .iter()
                .map(|&v| (v as Real - z as Real - mean).powi(2))
                .sum::<Real>()
                / n)
                .sqrt();
            // The expected σ over the plane's pixels (incidence grows off-axis).
            let want = (0..depth.len())
                .map(|i| {
                    let t = Vec3::new(0.0, 0.0, -1.0).dot(ray(i)).abs().acos();
                    model.sigma_m(z as Real, t).powi(2)
                })
                .sum::<Real>()
                / n;
            let want = want.sqrt();
            eprintln!(
                "z {z} m: mean {mean:.2e} m, std {std:.6} m, σ {want:.6} m, std/σ {:.4}",
                std / want
            );
            // 307 200 draws: the std's standard error is 0.13 % of σ; the mean's σ/554.
            // f32 storage adds at most 1.2e-7 z.
            assert!((std / want - 1.0).abs() < 0.01, "{std} vs {want}");
            assert!(mean.abs() < 5.0 * want / n.sqrt() + 1e-6, "{mean}");
        }
    }

    #[test]
    fn grazing_far_and_near_pixels_have_no_measurement() {
        let model = DepthNoise::default();
        let (depth, _, ray) = plane(2.0);
        // A plane tilted 80° away from the camera: beyond the default 75°.
        let tilt = 80f64.to_radians();
        let normal = vec![[tilt.sin() as f32, 0.0, -tilt.cos() as f32]; depth.len()];
        let noisy = model.apply(&depth, &normal, &ray, SEED);
        let centre = 240 * 640 + 320;
        assert_eq!(noisy[centre], 0.0);
        let (far, normal, ray) = plane(4.5);
        assert!(model
            .apply(&far, &normal, &ray, SEED)
            .iter()
            .all(|&v| v == 0.0));
        let (near, normal, ray) = plane(0.3);
        assert!(model
            .apply(&near, &normal, &ray, SEED)
            .iter()
            .all(|&v| v == 0.0));
        let (ok, normal, ray) = plane(2.0);
        let noisy = model.apply(&ok, &normal, &ray, SEED);
        // Quantised to millimetres.
        assert!(noisy
            .iter()
            .all(|&v| ((v as Real * 1000.0) - (v as Real * 1000.0).round()).abs() < 1e-3));
    }

    #[test]
    fn checks_name_the_parameter() {
        let bad = DepthNoise {
            max_range_m: 0.2,
            ..DepthNoise::default()
        };
        assert_eq!(bad.check().unwrap_err().0, "max_range_m");
        let bad = DepthNoise {
            sigma_base_m: -1.0,
            ..DepthNoise::default()
        };
        assert_eq!(bad.check().unwrap_err().0, "sigma_base_m");
        // Each finite, σ not: refused, not written as infinite depths.
        let bad = DepthNoise {
            sigma_base_m: 1e308,
            sigma_quadratic_per_m: 1e308,
            max_range_m: 1e3,
            ..DepthNoise::default()
        };
        let (key, what) = bad.check().unwrap_err();
        assert_eq!(key, "sigma_base_m");
        assert!(what.contains("σ is finite"), "{what}");
        assert!(DepthNoise::default().check().is_ok());
        assert!(DepthNoise::none().check().is_ok());
    }

    fn frame() -> impl Strategy<Value = (Vec<f32>, Vec<[f32; 3]>)> {
        prop::collection::vec(
            (
                prop_oneof![Just(0.0f32), 0.01f32..20.0],
                -1.0f32..1.0,
                -1.0f32..1.0,
            ),
            1..200,
        )
        .prop_map(|px| {
            let depth = px.iter().map(|p| p.0).collect();
            let normal = px
                .iter()
                .map(|p| {
                    let n = Vec3::new(p.1 as Real, p.2 as Real, -1.0).normalize();
                    [n.x as f32, n.y as f32, n.z as f32]
                })
                .collect();
            (depth, normal)
        })
    }

    proptest! {
        #[test]
        fn zero_noise_changes_nothing((depth, normal) in frame(), seed in any::<u64>()) {
            let seed = NoiseSeed { seed, camera: "d", frame: 0 };
            let out = DepthNoise::none().apply(&depth, &normal, |_| Vec3::Z, seed);
            prop_assert_eq!(out, depth);
        }

        #[test]
        fn same_seed_same_noise((depth, normal) in frame(), seed in any::<u64>(), frame_no in 0u32..1000) {
            let model = DepthNoise { min_range_m: 0.0, max_range_m: 100.0, ..DepthNoise::default() };
            let s = NoiseSeed { seed, camera: "d", frame: frame_no };
            let a = model.apply(&depth, &normal, |_| Vec3::Z, s);
            let b = model.apply(&depth, &normal, |_| Vec3::Z, s);
            prop_assert_eq!(&a, &b);
            // Another frame draws other noise wherever there is a measurable surface.
            let other = model.apply(&depth, &normal, |_| Vec3::Z, NoiseSeed { frame: frame_no + 1, ..s });
            let measured = a.iter().filter(|&&v| v > 0.0).count();
            if measured >= 20 {
                prop_assert_ne!(a, other);
            }
        }
    }
}
