//! The local-map alternative (paper Tab. 2 ablation): an ego-centred occupancy patch in front
//! of the agent, sampled from the walkable map and the dynamic obstacles.
//!
//! Patch frame: x forward (heading), y left. Cells `rows × cols`, `cell_m` each, covering
//! x ∈ [−behind_m, −behind_m + rows·cell_m), y centred. Value 1 where the cell centre is blocked
//! (non-walkable or inside an obstacle), 0 where free. Row-major, row 0 nearest behind.

use glam::DVec2;

use super::ego::{EgoPose2, EgoSensor, SensingWorld};

#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LocalMapSettings {
    pub rows: usize,
    pub cols: usize,
    pub cell_m: f64,
    pub behind_m: f64,
}

impl Default for LocalMapSettings {
    fn default() -> Self {
        // 16 × 16 cells of 0.25 m: 4 m × 4 m, 1 m behind and 3 m ahead.
        Self {
            rows: 16,
            cols: 16,
            cell_m: 0.25,
            behind_m: 1.0,
        }
    }
}

/// Ego-centred occupancy patch sensor.
#[derive(Debug, Clone, Default)]
pub struct LocalMap {
    pub settings: LocalMapSettings,
}

impl EgoSensor for LocalMap {
    fn dim(&self) -> usize {
        self.settings.rows * self.settings.cols
    }

    fn observe_into(&self, world: &SensingWorld, pose: EgoPose2, out: &mut [f32]) {
        let s = self.settings;
        let rot = DVec2::from_angle(pose.heading_rad);
        for r in 0..s.rows {
            for c in 0..s.cols {
                let local = DVec2::new(
                    -s.behind_m + (r as f64 + 0.5) * s.cell_m,
                    (c as f64 + 0.5 - s.cols as f64 / 2.0) * s.cell_m,
                );
                let p = pose.position + rot.rotate(local);
                let blocked =
                    !world.map.is_walkable_at(p) || world.obstacles.iter().any(|o| o.contains(p));
                out[r * s.cols + c] = blocked as u8 as f32;
            }
        }
    }
}
