//! Policy training and the batched environment it runs: the egocentric environment in which
//! many bodies, driven one 0.5 s primitive at a time by latents of the motion model, walk to
//! goals past obstacles they see through 32 rays (each one a [`crate::walker`] walker: its
//! observation, its judge, its step); the actor-critic network and PPO; and the evaluation of
//! controllers over held-out episodes.
//!
//! Depends on `walker` (the one walker every episode is), `motion::cvae` (decoding), `body`,
//! `scene` and `sensing`. Nothing here renders.
//!
//! - acting on the CPU: `actor` and `row_product` (the policy in f32, a `walker::Policy`),
//!   `weights` (the shipped policy, loading and saving);
//! - the environment: `env` (episodes, batched), `sampling` (best of K latents for every
//!   episode at once);
//! - training: `net` (the actor-critic in burn), `ppo` (its stages and checkpoints) over the
//!   environment's scenes — generated ones (`crate::scene::generated`: box scenes, crossings,
//!   floor plans) and `fixed_scene` (a scene file with start/goal pairs); `train_job`
//!   (`egogen train policy`: the parts a plan names loaded, the policy trained);
//! - evaluation: `held_out` (a controller over held-out episodes, training's validation
//!   among them); the `egogen policy` commands' jobs are `crate::eval::policy_commands` (on
//!   `crate::eval::policy_tasks`), the paper's tables `crate::eval`'s;
//! - tests only: `env_tests` (the environment's episodes, observations, walls and guides).

pub(crate) mod actor;
pub(crate) mod env;
#[cfg(test)]
pub(crate) mod env_tests;
pub(crate) mod fixed_scene;
pub(crate) mod held_out;
pub mod net;
pub mod ppo;
pub(crate) mod row_product;
pub(crate) mod sampling;
pub(crate) mod train_job;
pub mod weights;

pub use actor::Actor;
pub use env::{EnvSettings, PolicyEnv};
