//! egogen: egocentric synthetic data for head-mounted cameras.
//!
//! Modules follow the data flow: `scene` (meshes, walkable map) → `sensing` (ego rays);
//! `body` (SMPL-X skeleton, skinning, eye anchor) →
//! `motion` (pose sequences and their files, the motion-primitive model) → `policy` (the
//! locomotion environment, rewards and controllers) → `synth` (posed sequences, CPF trajectories);
//! `eval` runs the paper's evaluation scenarios through `synth` and measures them;
//! `preview` draws PNG pictures for people;
//! `cli` holds the command-line and config plumbing and no domain logic; `run_job` is
//! `egogen-run`'s job, from a config through `supervisor` to a dataset.

pub mod atomic_file;
pub mod body;
pub mod camera;
pub mod campaign;
pub mod cli;
pub mod eval;
pub mod export;
pub mod exr_file;
pub mod inspect;
pub mod manifest;
pub mod math;
pub mod memory;
pub mod motion;
pub mod npz;
pub mod parser_guard;
pub mod paths;
pub mod plan;
pub mod policy;
pub mod preview;
pub mod progress;
pub mod render;
pub mod rig;
pub mod run_job;
pub mod scene;
pub mod sensing;
pub mod supervisor;
pub mod synth;
pub mod vertex_cache;
pub mod walker;
