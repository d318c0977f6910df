//! Scenes: triangle meshes in metres (z up) with named objects, the floor, the walkable map,
//! start/goal sampling, what each object is and where one may sit, body–scene collision terms,
//! and scenes drawn from a seed. Hands off to `sensing` (rays over the walkable map). Nothing
//! here knows about bodies or policies.
//!
//! Here: `mesh` (a triangle soup with per-triangle object ids), `load` (glTF/GLB, OBJ and PLY
//! files into a mesh in metres, z up), `ceiling` (whether a scene has one, and the one added
//! when not), `floor` (the floor height), `walkable` (the walkable map: occupancy and 2D signed
//! distance), `sdf2d` (the exact distance transform behind it), `mesh_distance` (exact signed
//! distance to the triangles), `sdf3d` (the 3D signed distance field on voxels), `penetration`
//! (body–scene collision terms: 3D SDF or the 2D box test), `obstacle` (2D boxes and circles
//! that move or are not in the mesh), `sampler` (seeded start/goal sampling), `path_plan` (A*
//! walking paths on the walkable map and the guide), `seen_map` (what a walker has seen of the
//! map), `object_class` (the one vocabulary of what an object is, which seats, materials and
//! generated scenes read), `seats` (the places to sit), `chair_pull` (places on chairs pulled out
//! from their tables), `small_object` (what people pick up:
//! egogen's own kinds, solids and sizes, and the scene's own small things on a floor), `generated` (procedural scenario
//! scenes), `dwelling` (furnished dwellings generated from a seed and the furniture catalogue,
//! the `dwelling:SEED` scene source).

pub(crate) mod ceiling;
pub(crate) mod chair_pull;
pub mod dwelling;
pub(crate) mod floor;
pub mod generated;
pub(crate) mod load;
pub(crate) mod mesh;
pub mod mesh_distance;
pub(crate) mod object_class;
pub(crate) mod obstacle;
pub(crate) mod path_plan;
pub(crate) mod penetration;
pub(crate) mod sampler;
pub(crate) mod sdf2d;
pub(crate) mod sdf3d;
pub(crate) mod seats;
pub(crate) mod seen_map;
pub(crate) mod small_object;
pub(crate) mod walkable;

pub use generated::scenario::{scenario, ScenarioKind, ScenarioScene};
pub(crate) use load::scene_frame_warning;
pub use load::{load_scene, walkable_map, SceneError, SceneFrame, UpAxis};
pub use mesh::{ObjectId, ObjectOrientation, SceneMesh, SceneObject};
pub(crate) use object_class::ObjectClass;
pub use obstacle::{MovingObstacle, Obstacle2, ObstacleSolid};
pub(crate) use path_plan::{plan_path, Guide, PathField};
pub use penetration::{blocked_cells_in_box, sdf_penetration, Penetration};
pub(crate) use sampler::sample_start_goals_in;
pub use sampler::{sample_start_goals, StartGoal};
pub use sdf3d::SceneSdf;
pub(crate) use seats::{find_seats, Seat, SeatSettings};
pub(crate) use seen_map::{guide_aim_remembered, SeenMap};
pub use walkable::{indoor_map, WalkableMap, WalkableSettings};
