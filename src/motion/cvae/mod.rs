//! The motion-primitive model: a conditional VAE (burn) over canonical primitives of 20
//! frames at 40 fps. Given the 2 seed frames and a 128-D latent, an autoregressive GRU-cell
//! decoder writes the other 18 frames (6D rotations of global orient and the 21 body joints,
//! pelvis translation) in the primitive's canonical frame. Skinning in f64 stays `body`'s,
//! primitives and canonical frames `primitive`'s; the paper's evaluation of controllers is
//! `crate::eval`, a controller over held-out episodes `policy::held_out`.
//!
//! The network and its training: `net` (MLP encoder, residual GRU-cell decoder conditioned on
//! seed, latent and floor height), `features` (what it reads and writes per frame, and the way
//! back to SMPL-X parameters), `data` (clips cut into primitives and chains as `f32` features),
//! `tensor_body` (the body as tensors: FK and the 67 markers, differentiable), `loss` (pose, FK
//! markers, velocity, foot skate and floor, robust KL), `rollout` (chaining primitives on
//! tensors), `pool` (the seeds prior fine-tuning starts chains from), `train` (single
//! primitives, then rollout over chains, then prior fine-tuning), `train_error` (why a training
//! run stopped), `checkpoint` (what `--resume` continues from), `weights` (safetensors files
//! that carry their architecture).
//!
//! Using it: `infer` (the inference API: seeds and latents to primitives in the world, with
//! markers and CPF), `decoder_f32` (the decoder in plain f32 for few primitives at a time),
//! `half_matvec` (one primitive's products with f16 weights), `sampler` (best-of-K
//! random-latent sampling), `pace` (pace and turn of primitives), `control` (latents chosen for
//! a target velocity and heading by CEM; `control_tests`, tests only), `reach` (what the latent space reaches, as `egogen
//! motion control` prints it), `contact` (the foot-contact score), `measure` (a trained model's
//! measurements: held-out marker error, contact of batches and chains, long rollouts);
//! `model_tests` (tests only: the decoders, shipped weights, prior losses, training chains).

pub(crate) mod checkpoint;
pub(crate) mod contact;
pub(crate) mod control;
#[cfg(test)]
mod control_tests;
pub(crate) mod data;
pub(crate) mod decoder_f32;
pub mod features;
pub mod half_matvec;
pub mod infer;
pub mod loss;
pub mod measure;
#[cfg(test)]
mod model_tests;
pub(crate) mod net;
pub mod pace;
pub(crate) mod pool;
pub(crate) mod reach;
pub(crate) mod rollout;
pub(crate) mod sampler;
pub mod tensor_body;
pub mod train;
pub(crate) mod train_error;
pub mod weights;

pub(crate) use control::{CemSettings, LatentController};
pub use infer::{BodyContext, CanonicalSeed, DecodedPrimitive, MotionModel, PrimitiveSeed};
pub use net::{ArchConfig, PrimitiveVae};
pub(crate) use sampler::PlausibilityRules;
pub(crate) use sampler::{goal_ahead, goal_toward, BestOfK};
pub use train::train;
