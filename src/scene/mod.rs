//! Scenes: triangle meshes in metres (z up) with named objects, the floor, the walkable map
//! (occupancy + 2D signed distance) and start/goal sampling; procedural scenario scenes.
//!
//! Hands off to `sensing` (rays over the walkable map) and, for penetration, to `sdf3d`.
//! Nothing here knows about bodies or policies.

pub mod floor;
pub mod load;
pub mod mesh;
pub mod obstacle;
pub mod sampler;
pub mod scenario;
pub mod sdf2d;
pub mod walkable;

pub use load::{load_scene, walkable_map, SceneError, UpAxis};
pub use mesh::{ObjectId, SceneMesh, SceneObject};
pub use obstacle::{MovingObstacle, Obstacle2};
pub use sampler::{sample_start_goals, StartGoal};
pub use scenario::{scenario, Scenario, ScenarioKind};
pub use walkable::{WalkableMap, WalkableSettings};
