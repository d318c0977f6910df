//! The walker: one person walking, as every walker of egogen walks — an episode of policy
//! training and of `egogen policy eval`, a person of a take's crowd. Below `policy` (which
//! trains) and `synth` (which makes takes); uses `math`, `body`, `motion`, `scene` and
//! `sensing`.
//!
//! - `settings`: the one schema of how a walker steps (`[walker]`), its defaults and checks;
//! - `state`: one walking body as a controller sees it, and its observation;
//! - `controller`: what proposes the next primitive (the `Controller` trait: the policy, the
//!   sampling controller, the path follower) and the serde spec they are built from;
//! - `step`: the judge of a primitive and the one function by which every walker chooses
//!   the primitive it takes;
//! - `reward` and `pose_prior`: what the judge weighs (Tab. S2's terms, our pose prior);
//! - `seed_bank`: the mocap seeds every walker starts from.

pub(crate) mod controller;
pub mod pose_prior;
pub mod reward;
pub(crate) mod seed_bank;
pub(crate) mod settings;
pub mod state;
pub(crate) mod step;

pub use controller::{ControllerSpec, Policy, Steering};
pub use pose_prior::PosePrior;
pub use seed_bank::SeedBank;
pub use settings::WalkerSettings;
pub use state::ObsLayout;
pub(crate) use state::STATE_FRAME_DIM;
