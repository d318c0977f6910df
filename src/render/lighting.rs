//! Lighting egogen adds to a scene, drawn per sequence from a seed: the world light — a
//! uniform colour, or one of the CC0 HDRIs (Poly Haven) that ship inside the `bpy` wheel
//! (`bpy/4.5/datafiles/studiolights/world/`), rotated about the vertical and scaled — and a
//! point lamp near the top of the walls above the walk, its power drawn from a range. Lamps the
//! scene file has are imported with it and kept. Every choice is in the shard spec and the
//! annotations.

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde::Serialize;

use super::protocol::{PointLight, ShardLighting, WorldHdri};
use crate::math::random::uniform_open01;

/// The HDRIs in `bpy`'s `datafiles/studiolights/world/` (names without `.exr`).
pub const SHIPPED_HDRIS: [&str; 8] = [
    "city",
    "courtyard",
    "forest",
    "interior",
    "night",
    "studio",
    "sunrise",
    "sunset",
];

/// The world light asked for.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WorldChoice {
    /// A uniform colour (linear RGB).
    Colour([f64; 3]),
    /// One of [`SHIPPED_HDRIS`], drawn per sequence.
    RandomHdri,
    /// This one of [`SHIPPED_HDRIS`].
    Hdri(String),
}

/// How a sequence's lighting is drawn.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LightingPlan {
    pub world: WorldChoice,
    /// Range of the HDRI's strength (Blender's Background strength).
    pub hdri_strength: (f64, f64),
    /// Range of the point lamp's power (W).
    pub lamp_watts: (f64, f64),
    pub seed: u64,
}

impl Default for LightingPlan {
    /// What egogen rendered before lighting was configurable: a grey world and a 300 W lamp.
    fn default() -> Self {
        Self {
            world: WorldChoice::Colour([0.25; 3]),
            hdri_strength: (1.0, 1.0),
            lamp_watts: (300.0, 300.0),
            seed: 0,
        }
    }
}

fn between(rng: &mut ChaCha8Rng, (lo, hi): (f64, f64)) -> f64 {
    if hi > lo {
        lo + (hi - lo) * uniform_open01(rng)
    } else {
        lo
    }
}

impl LightingPlan {
    /// The lighting of one sequence, its lamp at `lamp_position` (m, z up).
    pub(crate) fn draw(&self, lamp_position: [f64; 3]) -> ShardLighting {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed ^ 0x11_6E7);
        let name = match &self.world {
            WorldChoice::Colour(_) => None,
            WorldChoice::RandomHdri => {
                let k = (uniform_open01(&mut rng) * SHIPPED_HDRIS.len() as f64) as usize;
                Some(SHIPPED_HDRIS[k.min(SHIPPED_HDRIS.len() - 1)].to_string())
            }
            WorldChoice::Hdri(n) => Some(n.clone()),
        };
        let world_hdri = name.map(|name| WorldHdri {
            name,
            rotation_rad: std::f64::consts::TAU * uniform_open01(&mut rng),
            strength: between(&mut rng, self.hdri_strength),
        });
        ShardLighting {
            world_rgb: match self.world {
                WorldChoice::Colour(rgb) => rgb,
                _ => [0.0; 3],
            },
            world_hdri,
            point_lights: vec![PointLight {
                position: lamp_position,
                watts: between(&mut rng, self.lamp_watts),
            }],
        }
    }
}
