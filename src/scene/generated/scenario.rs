//! Procedural scenario scenes (paper's evaluation settings): an empty floor for crossings, a
//! single static box, and a box moving across the floor.

use glam::DVec2;

use crate::math::Vec3;
use crate::scene::mesh::SceneMesh;
use crate::scene::obstacle::{MovingObstacle, Obstacle2};

/// A procedural scene: static mesh plus moving obstacles.
#[derive(Debug, Clone)]
pub struct ScenarioScene {
    pub name: &'static str,
    pub mesh: SceneMesh,
    pub moving: Vec<MovingObstacle>,
}

/// Which procedural scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScenarioKind {
    EmptyFloor,
    SingleBox,
    MovingBox,
}

/// Side of the square floor of every scenario (m), centred on the origin.
pub(crate) const FLOOR_SIZE_M: f64 = 16.0;

fn floor(mesh: &mut SceneMesh) {
    let h = FLOOR_SIZE_M / 2.0;
    let v = [
        Vec3::new(-h, -h, 0.0),
        Vec3::new(h, -h, 0.0),
        Vec3::new(h, h, 0.0),
        Vec3::new(-h, h, 0.0),
    ];
    mesh.add_object("floor", &v, &[[0, 1, 2], [0, 2, 3]]);
}

/// Builds a scenario.
pub fn scenario(kind: ScenarioKind) -> ScenarioScene {
    let mut mesh = SceneMesh::default();
    floor(&mut mesh);
    let mut moving = Vec::new();
    let name = match kind {
        ScenarioKind::EmptyFloor => "empty_floor",
        ScenarioKind::SingleBox => {
            mesh.add_box("box", Vec3::new(-0.5, -0.5, 0.0), Vec3::new(0.5, 0.5, 1.0));
            "single_box"
        }
        ScenarioKind::MovingBox => {
            moving.push(MovingObstacle {
                at_start: Obstacle2::Box {
                    centre: DVec2::new(0.0, -4.0),
                    half_extents: DVec2::splat(0.5),
                    yaw_rad: 0.0,
                },
                velocity_m_per_s: DVec2::new(0.0, 0.8),
            });
            "moving_box"
        }
    };
    ScenarioScene { name, mesh, moving }
}
