//! The egocentric depth image of the paper's Tab. 3 ablation ("Egocentric depth": a policy
//! that sees a depth image, encoded by a CNN, instead of the ray scan), computed by ray casting
//! the sensing world in Rust, without a renderer.
//!
//! The world is what every sensor here sees: the walkable map's blocked cells and the dynamic
//! obstacles, each stood up as a wall from the floor to `obstacle_height_m`, on a flat floor.
//! The camera sits level at `eye_height_m` above the floor at the ego pose, looking along its
//! heading. Pixels are equiangular: column `c` looks `half_fov_h_rad − 2·half_fov_h_rad·(c +
//! ½)/cols` to the left of the heading (column 0 on the left), row `r` `half_fov_v_rad −
//! 2·half_fov_v_rad·(r + ½)/rows` above the horizon (row 0 at the top). A pixel's value is the
//! length of its 3D ray to the first surface (floor or wall), capped at `max_range_m`, as the
//! ray scan writes it: `−1 + 2·range/max_range_m` (+1 where nothing is hit within range, −1 from
//! inside an obstacle). Row-major, `rows × cols` per observed pose.
//!
//! Each column is one 2D cast (the walls are vertical, so every row of a column meets the same
//! wall footprint first); the rows then choose floor, wall or nothing. By default the image
//! spans the ray scan's 180° in 32 columns, so the ablation differs from the paper's sensing in
//! its representation (a 16 × 32 image for a CNN instead of 32 values for a GRU), not its
//! field of view.

use glam::DVec2;

use super::ego::{EgoPose2, EgoSensor, SensingWorld};
use super::ray::Ray2;

/// Settings of the depth image.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DepthImageSettings {
    pub rows: usize,
    pub cols: usize,
    /// Half the horizontal field of view (rad).
    pub half_fov_h_rad: f64,
    /// Half the vertical field of view (rad), about the horizon.
    pub half_fov_v_rad: f64,
    /// Longest ray (m).
    pub max_range_m: f64,
    /// The camera's height above the floor (m).
    pub eye_height_m: f64,
    /// Height of every wall and obstacle (m).
    pub obstacle_height_m: f64,
}

impl Default for DepthImageSettings {
    /// 16 × 32 pixels over the ray scan's 180° and ±45° about the horizon, 7 m, eyes at 1.6 m,
    /// obstacles 2 m tall.
    fn default() -> Self {
        Self {
            rows: 16,
            cols: 32,
            half_fov_h_rad: std::f64::consts::FRAC_PI_2,
            half_fov_v_rad: std::f64::consts::FRAC_PI_4,
            max_range_m: 7.0,
            eye_height_m: 1.6,
            obstacle_height_m: 2.0,
        }
    }
}

impl DepthImageSettings {
    /// What is wrong with the settings, if anything (`None`: usable).
    pub(crate) fn problem(&self) -> Option<String> {
        let finite_positive = |name: &str, v: f64| {
            (!(v.is_finite() && v > 0.0)).then(|| format!("{name} must be > 0, got {v}"))
        };
        if self.rows == 0 || self.cols == 0 {
            return Some(format!(
                "rows and cols must be ≥ 1, got {} × {}",
                self.rows, self.cols
            ));
        }
        if !(0.0..=std::f64::consts::PI).contains(&self.half_fov_h_rad) {
            return Some(format!(
                "half_fov_h_rad must be in [0, π], got {}",
                self.half_fov_h_rad
            ));
        }
        if !(0.0..std::f64::consts::FRAC_PI_2).contains(&self.half_fov_v_rad) {
            return Some(format!(
                "half_fov_v_rad must be in [0, π/2), got {}",
                self.half_fov_v_rad
            ));
        }
        finite_positive("max_range_m", self.max_range_m)
            .or_else(|| finite_positive("eye_height_m", self.eye_height_m))
            .or_else(|| finite_positive("obstacle_height_m", self.obstacle_height_m))
    }

    /// Column `c`'s angle to the left of the heading (rad).
    fn azimuth(&self, c: usize) -> f64 {
        self.half_fov_h_rad - 2.0 * self.half_fov_h_rad * (c as f64 + 0.5) / self.cols as f64
    }

    /// Row `r`'s angle above the horizon (rad).
    fn elevation(&self, r: usize) -> f64 {
        self.half_fov_v_rad - 2.0 * self.half_fov_v_rad * (r as f64 + 0.5) / self.rows as f64
    }
}

/// The depth-image sensor.
#[derive(Debug, Clone)]
pub struct DepthImage {
    settings: DepthImageSettings,
    /// Per row: the sine and cosine of its elevation (the same for every observation).
    rows: Vec<(f64, f64)>,
    /// Per column: its direction relative to the heading.
    cols: Vec<DVec2>,
}

impl Default for DepthImage {
    fn default() -> Self {
        Self::new(DepthImageSettings::default())
    }
}

impl DepthImage {
    pub(crate) fn new(settings: DepthImageSettings) -> Self {
        Self {
            settings,
            rows: (0..settings.rows)
                .map(|r| settings.elevation(r).sin_cos())
                .collect(),
            cols: (0..settings.cols)
                .map(|c| DVec2::from_angle(settings.azimuth(c)))
                .collect(),
        }
    }

    /// Its settings (fixed at [`Self::new`]: the angles are computed from them once).
    pub(crate) fn settings(&self) -> DepthImageSettings {
        self.settings
    }

    /// Ray length (m) per pixel, row-major, `max_range_m` where nothing is hit within range.
    pub(crate) fn ranges(&self, world: &SensingWorld, pose: EgoPose2) -> Vec<f64> {
        let mut out = vec![0.0; self.settings.rows * self.settings.cols];
        self.each_range(world, pose, |k, range| out[k] = range);
        out
    }

    /// Calls `put(pixel, range)` for every pixel (row-major index, ray length in m).
    fn each_range(&self, world: &SensingWorld, pose: EgoPose2, mut put: impl FnMut(usize, f64)) {
        let s = self.settings;
        let heading = DVec2::from_angle(pose.heading_rad);
        for (c, offset) in self.cols.iter().enumerate() {
            let ray = Ray2 {
                origin: pose.position,
                dir: heading.rotate(*offset),
            };
            // The wall a column meets first, by horizontal distance.
            let wall = world.cast(ray, s.max_range_m);
            for (r, &(sin_e, cos_e)) in self.rows.iter().enumerate() {
                // Horizontal distance to the floor (looking down) and to the wall where the
                // ray still passes below its top.
                let floor = (sin_e < 0.0).then(|| s.eye_height_m * cos_e / -sin_e);
                let wall =
                    wall.filter(|d| s.eye_height_m + d * sin_e / cos_e <= s.obstacle_height_m);
                let horizontal = match (floor, wall) {
                    (Some(f), Some(w)) => Some(f.min(w)),
                    (f, w) => f.or(w),
                };
                put(
                    r * s.cols + c,
                    horizontal.map_or(s.max_range_m, |h| (h / cos_e).min(s.max_range_m)),
                );
            }
        }
    }
}

impl EgoSensor for DepthImage {
    fn dim(&self) -> usize {
        self.settings.rows * self.settings.cols
    }

    fn observe_into(&self, world: &SensingWorld, pose: EgoPose2, out: &mut [f32]) {
        let range = self.settings.max_range_m;
        self.each_range(world, pose, |k, d| {
            out[k] = (-1.0 + 2.0 * d / range) as f32;
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Obstacle2, WalkableMap};

    fn open_floor() -> WalkableMap {
        // 20 m × 20 m of floor centred on the origin (0.1 m cells).
        WalkableMap::from_walkable(DVec2::splat(-10.0), 0.1, 200, 200, vec![true; 200 * 200])
    }

    #[test]
    fn a_wall_ahead_fills_the_middle_columns_at_its_distance_and_the_floor_the_rest() {
        let map = open_floor();
        // A wide wall 3 m ahead of the origin (the sensor looks along +x), 2 m tall.
        let wall = Obstacle2::Box {
            centre: DVec2::new(3.5, 0.0),
            half_extents: DVec2::new(0.5, 5.0),
            yaw_rad: 0.0,
        };
        let sensor = DepthImage::default();
        let s = sensor.settings();
        let world = SensingWorld {
            map: &map,
            obstacles: std::slice::from_ref(&wall),
        };
        let pose = EgoPose2 {
            position: DVec2::ZERO,
            heading_rad: 0.0,
        };
        let ranges = sensor.ranges(&world, pose);
        // The middle columns look almost straight ahead: horizontal distance 3 m.
        let c = s.cols / 2;
        let a = s.azimuth(c);
        for r in 0..s.rows {
            let e = s.elevation(r);
            let wall_h = 3.0 / a.cos();
            let floor_h = if e < 0.0 {
                s.eye_height_m / (-e).tan()
            } else {
                f64::INFINITY
            };
            let top = s.eye_height_m + wall_h * e.tan();
            let expected = if top > s.obstacle_height_m {
                s.max_range_m
            } else {
                (wall_h.min(floor_h) / e.cos()).min(s.max_range_m)
            };
            let got = ranges[r * s.cols + c];
            assert!(
                (got - expected).abs() < 1e-9,
                "row {r}: {got} vs {expected}"
            );
        }
        // Steep rows see the floor: 1.6 m below the eye at the lowest row's angle.
        let low = s.elevation(s.rows - 1);
        let floor = s.eye_height_m / (-low).sin();
        assert!((ranges[(s.rows - 1) * s.cols] - floor).abs() < 1e-9);
        // Rows above the wall's top see nothing within range straight ahead, and the wall's
        // top edge lies where its angle says.
        assert_eq!(ranges[c], s.max_range_m);
        let obs = sensor.observe(&world, pose);
        assert!(obs.iter().all(|v| (-1.0..=1.0).contains(v)));
        assert_eq!(obs.len(), s.rows * s.cols);
    }

    #[test]
    fn turning_the_head_turns_the_image_and_extreme_settings_stay_finite() {
        let map = open_floor();
        let post = Obstacle2::Circle {
            centre: DVec2::new(0.0, 2.0),
            radius_m: 0.3,
        };
        let world = SensingWorld {
            map: &map,
            obstacles: std::slice::from_ref(&post),
        };
        let sensor = DepthImage::default();
        let s = sensor.settings();
        // Facing +x the post is 90° to the left: column 0's side. Facing +y it is ahead.
        let left = sensor.ranges(
            &world,
            EgoPose2 {
                position: DVec2::ZERO,
                heading_rad: 0.0,
            },
        );
        let ahead = sensor.ranges(
            &world,
            EgoPose2 {
                position: DVec2::ZERO,
                heading_rad: std::f64::consts::FRAC_PI_2,
            },
        );
        let row = s.rows / 2; // just below the horizon: the post, not the floor
        let side = left[row * s.cols] * s.elevation(row).cos();
        assert!((1.7..1.9).contains(&side), "{side}");
        let mid = s.cols / 2;
        assert!(
            ahead[row * s.cols + mid] < 1.8,
            "{}",
            ahead[row * s.cols + mid]
        );
        assert!(left[row * s.cols + mid] > 6.0);
        // Extremes: a field of view at its limits, a tiny image, far from the origin.
        for settings in [
            DepthImageSettings {
                rows: 1,
                cols: 1,
                ..s
            },
            DepthImageSettings {
                half_fov_h_rad: std::f64::consts::PI,
                half_fov_v_rad: std::f64::consts::FRAC_PI_2 - 1e-4,
                ..s
            },
        ] {
            assert_eq!(settings.problem(), None);
            let sensor = DepthImage::new(settings);
            for position in [DVec2::ZERO, DVec2::new(9.9, -9.9)] {
                let v = sensor.observe(
                    &world,
                    EgoPose2 {
                        position,
                        heading_rad: 3.0,
                    },
                );
                assert!(v.iter().all(|x| x.is_finite() && (-1.0..=1.0).contains(x)));
            }
        }
        assert!(DepthImageSettings {
            half_fov_v_rad: std::f64::consts::FRAC_PI_2,
            ..s
        }
        .problem()
        .is_some());
    }
}
