//! egogen: egocentric synthetic data for head-mounted cameras.
//!
//! Modules follow the data flow (docs/ARCHITECTURE.md; `tests/layering.rs` keeps every module
//! to the layers below it), grouped by layer:
//! - shared ground, below everything: `math` (aliases, frame conventions, rotations, seeded
//!   draws, least squares, pose splines), `paths` (where shipped files and the cache are),
//!   `atomic_file` (outputs never replaced unasked nor left half-written), `parser_guard`
//!   (third-party parsers' panics caught as errors), `memory` (the memory a run may plan for),
//!   `progress` (progress bars and log lines), `npz` (NumPy arrays read as `f64`), `exr_file`
//!   (EXR channels read into named planes), `manifest` (an output folder's files with sizes and
//!   SHA-256), `vertex_cache` (the files bodies reach Blender in: faces and PC2 point caches);
//! - cameras: `camera` (lens models: camera-frame points ↔ pixels) → `rig` (which cameras a
//!   headset carries and where they sit relative to the eye anchor);
//! - world and people: `scene` (meshes, walkable map, what each object is) → `sensing` (ego
//!   rays); `body` (SMPL-X skeleton, skinning, eye anchor) → `motion` (pose sequences and their
//!   files, the motion-primitive model, joins and the steady head) → `walker` (one person
//!   walking: settings, observation, controllers, the judge and the step every walker takes) →
//!   `policy` (training: the batched environment, the network, PPO) → `synth` (takes: crowds of
//!   people walking and doing things, their tracks and sequence folders); `eval` runs the
//!   paper's evaluation through `synth` and `policy` and measures it;
//! - outputs: `render` draws frames in Blender, `export` turns a take into its outputs, `plan`
//!   holds checked run plans, `supervisor` turns a plan into a dataset, `campaign` runs many
//!   takes;
//! - for people and the command line: `preview` draws PNG pictures, `inspect` looks inside EXR
//!   files (channels, statistics, previews); `cli` holds the command-line and config plumbing and
//!   no domain logic (each command's job lives in the module whose data it is); `run_job` is
//!   `egogen-run`'s job; `commands`, at the top, holds the two binaries' command lines (they
//!   parse and call; `src/bin/` only calls them).

// Items are pub(crate) unless a binary, test or bench uses them (tests/code_shape.rs); the docs
// are built with them (`cargo doc --document-private-items`), where a public item's link to a
// crate-private one resolves.
#![allow(rustdoc::private_intra_doc_links)]

pub(crate) mod atomic_file;
pub mod body;
pub mod camera;
pub mod campaign;
pub mod cli;
pub mod commands;
pub(crate) mod eval;
pub mod export;
pub mod exr_file;
pub mod inspect;
pub mod manifest;
pub mod math;
pub(crate) mod memory;
pub mod motion;
pub(crate) mod npz;
pub(crate) mod parser_guard;
pub(crate) mod paths;
pub mod plan;
pub mod policy;
pub mod preview;
pub(crate) mod progress;
pub mod render;
pub mod rig;
pub(crate) mod run_job;
pub mod scene;
pub mod sensing;
pub mod supervisor;
pub mod synth;
pub mod vertex_cache;
pub mod walker;
