//! Scenes drawn from a seed rather than read from a file, in one place: the policy's training
//! scenes (`box_scene`: EgoGen's single-box scenes; `crossing_scene`: another person crossing
//! the path; `room_scene`: procedural floor plans, also a campaign's generated scenes and the
//! evaluation's held-out dwellings) and the paper's evaluation settings as scene meshes
//! (`scenario`: an empty floor, a static box, a moving box). Each is a function of its
//! settings and a generator; none reads a file.

pub(crate) mod box_scene;
pub(crate) mod crossing_scene;
pub mod room_scene;
pub mod scenario;
