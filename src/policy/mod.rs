//! Locomotion control: the egocentric environment in which a body, driven one 0.5 s primitive
//! at a time by latents of the motion model, walks to a goal past obstacles it sees through
//! 32 rays; the reward of Tab. S2 with our own pose prior; the sampling controller (best of K
//! latents by the reward); and the evaluation of controllers over held-out episodes.
//!
//! Depends on `motion::cvae` (decoding), `body` (markers, CPF), `scene` (walkable map,
//! collision) and `sensing` (rays). Nothing here renders.
//!
//! By when it runs:
//! - acting (every take): `weights` (the shipped policy, loading and saving), `walker` (one
//!   body as a controller sees it), `walker_settings` (the one schema of a walker's settings,
//!   `[walker]`), `step` (the walker's step: one judge of a primitive and
//!   the one function by which every walker — training, evaluation, a take's agents — chooses
//!   the primitive it takes), `actor` and `row_product` (the policy on the CPU in f32),
//!   `sampling` (best of K latents), the environment's observation and reward (`env`,
//!   `reward`, `pose_prior`);
//! - training: `net` (the actor-critic in burn), `ppo` (its stages and checkpoints) over the
//!   environment's scenes — generated ones (`crate::scene::generated`: box scenes, crossings,
//!   floor plans) and `fixed_scene` (a scene file with start/goal pairs);
//! - evaluation: `held_out` (a controller over held-out episodes, training's validation
//!   among them); the `egogen policy` commands' jobs are `crate::eval::policy_tasks`, the
//!   paper's tables `crate::eval`'s.

pub mod actor;
pub mod env;
pub mod fixed_scene;
pub mod held_out;
pub mod net;
pub mod pose_prior;
pub mod ppo;
pub mod reward;
pub mod row_product;
pub mod sampling;
pub(crate) mod step;
pub mod walker;
pub mod walker_settings;
pub mod weights;

pub use actor::Actor;
pub use env::{EnvSettings, ObsLayout, PolicyEnv, SeedBank};
pub use pose_prior::PosePrior;
pub use walker_settings::WalkerSettings;
