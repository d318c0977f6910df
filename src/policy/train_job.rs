//! `egogen train policy`'s job: the motion model, pose prior, seeds and scenes a training plan
//! names loaded, the policy trained with PPO (`ppo`), and what was trained said. `cli` loads
//! the training configs.

use std::path::Path;

use anyhow::Result;

use super::ppo::PolicyTrainPlan;
use crate::body::BodyModel;
use crate::motion::cvae::train::TrainPlan;

/// Trains the policy `plan` describes (`quiet`: no progress bar; `resume`: from its checkpoint;
/// `force`: over its outputs); `load_motion_plan` reads the motion training config it names.
pub(crate) fn train_policy(
    mut plan: PolicyTrainPlan,
    quiet: bool,
    resume: bool,
    force: bool,
    load_motion_plan: impl FnOnce(&Path) -> Result<TrainPlan>,
) -> Result<()> {
    use super::env::EnvParts;
    use super::ppo::train_policy;
    use crate::motion::cvae::train::evaluation_sets;
    use crate::motion::cvae::{BodyContext, MotionModel};
    use crate::walker::PosePrior;
    use crate::walker::SeedBank;
    let body = BodyModel::load(&plan.body_model)?;
    let ctx = BodyContext::new(&body, &[])?;
    let model = MotionModel::load(&plan.motion_weights)?;
    plan.arch.latent_dim = model.latent_dim();
    let prior = PosePrior::load(&plan.pose_prior)?;
    let motion_plan = load_motion_plan(&plan.motion_config)?;
    let (train_set, _) = evaluation_sets(&motion_plan, &body, true)?;
    let bank = SeedBank::from_set(&train_set);
    // The scene's 3D SDF only where a stage tests penetration by Eq. 11.
    let sdf_voxel_m = plan
        .stages
        .iter()
        .any(|s| s.env.scene_test_vertices > 0)
        .then_some(crate::scene::sdf3d::DEFAULT_VOXEL_M);
    let fixed = plan
        .scene
        .as_ref()
        .map(|s| super::fixed_scene::fixed_scene(s, sdf_voxel_m))
        .transpose()?;
    let dwellings = plan
        .dwellings
        .iter()
        .map(|s| super::fixed_scene::fixed_scene(s, None))
        .collect::<Result<Vec<_>>>()?;
    let parts = EnvParts {
        model: &model,
        body: &ctx,
        bank: &bank,
        prior: &prior,
        fixed: fixed.as_ref(),
        dwellings: &dwellings,
    };
    let report = train_policy(&plan, &parts, !quiet, resume, force)?;
    println!(
        "trained {} parameters for {} updates ({} env steps) in {:.0} s; best validation return {}",
        report.parameters,
        report.updates,
        report.env_steps,
        report.seconds,
        report
            .best_validation_return
            .map_or("n/a".into(), |r| format!("{r:.3}"))
    );
    println!(
        "wrote {} and {}",
        plan.weights_out.display(),
        plan.log_out.display()
    );
    Ok(())
}
