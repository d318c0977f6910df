//! The motion-primitive model: a conditional VAE (burn) over canonical primitives of 20
//! frames at 40 fps. Given the 2 seed frames and a 128-D latent, an autoregressive GRU-cell
//! decoder writes the other 18 frames (6D rotations of global orient and the 21 body joints,
//! pelvis translation) in the primitive's canonical frame.
//!
//! Owns the network, its losses (pose, FK markers through a tensor rig, velocity, foot skate and
//! floor, robust KL), training (single primitives, then rollout over chains, then prior
//! fine-tuning), weights files, the inference API (burn's decoder beside a plain f32 one for
//! few primitives at a time, reading f16 weights for one alone), best-of-K random-latent sampling, the pace
//! and turn of primitives, and latents chosen for a target velocity and heading (`control`);
//! skinning in f64 stays `body`'s, primitives and canonical frames `primitive`'s. A trained
//! model's measurements (held-out marker error, contact of batches and chains, long rollouts)
//! are `measure`; the paper's evaluation of controllers is `crate::eval`, a controller over
//! held-out episodes `policy::held_out`.

pub(crate) mod checkpoint;
pub(crate) mod contact;
pub mod control;
pub mod data;
pub(crate) mod decoder_f32;
pub mod features;
pub mod half_matvec;
pub mod infer;
pub mod loss;
pub mod measure;
pub mod net;
pub mod pace;
pub mod pool;
pub(crate) mod reach;
pub mod rollout;
pub mod sampler;
pub mod tensor_body;
pub mod train;
pub(crate) mod train_error;
pub mod weights;

pub use control::{CemSettings, LatentController, PaceTarget};
pub use infer::{BodyContext, CanonicalSeed, DecodedPrimitive, MotionModel, PrimitiveSeed};
pub use net::{ArchConfig, PrimitiveVae};
pub use sampler::{goal_ahead, goal_toward, BestOfK, Plausibility, PlausibilityRules};
pub use train::{train, TrainPlan, TrainReport};
pub use weights::WeightsError;
