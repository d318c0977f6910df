//! The speed suite: its scenario rows over sampling K, and its knobs (rays per scan, policy
//! width, the apartment's SDF resolution).

use std::path::Path;

use anyhow::Result;

use super::policies::{box_and_crossing_rows, table_policy, write_policy_rows};
use super::table1::run_rows;
use super::table2::{table2_scene, table2_settings};
use super::{bar, chosen_controllers, EvalJob, SuiteParts};
use crate::eval::files::PolicyRow;
use crate::eval::scenarios::Scenario;
use crate::eval::suite::NamedController;

/// The speed suite's ray-count knob: policies trained with the budget and settings of
/// `configs/train_policy.toml` (whose policy is the 32-ray row), differing only in the rays
/// per scan. Label, weights, config.
const RAYS_POLICIES: [(&str, &str, &str); 4] = [
    (
        "8 rays",
        "assets/policy/knobs/rays_8.safetensors",
        "configs/knobs/rays_8.toml",
    ),
    (
        "16 rays",
        "assets/policy/knobs/rays_16.safetensors",
        "configs/knobs/rays_16.toml",
    ),
    (
        "32 rays (the paper's)",
        "assets/policy/policy.safetensors",
        "configs/train_policy.toml",
    ),
    (
        "64 rays",
        "assets/policy/knobs/rays_64.safetensors",
        "configs/knobs/rays_64.toml",
    ),
];

/// The speed suite's policy-width knob: policies trained with the budget and settings of
/// `configs/train_policy.toml` (whose policy is the 128-wide row), differing only in the GRU
/// width H (the MLPs are 2H + 4F wide). Label, weights, config.
const WIDTH_POLICIES: [(&str, &str, &str); 3] = [
    (
        "H = 64",
        "assets/policy/knobs/width_64.safetensors",
        "configs/knobs/width_64.toml",
    ),
    (
        "H = 128 (shipped width)",
        "assets/policy/policy.safetensors",
        "configs/train_policy.toml",
    ),
    (
        "H = 256",
        "assets/policy/knobs/width_256.safetensors",
        "configs/knobs/width_256.toml",
    ),
];

/// The speed suite's SDF-resolution knob: voxel sizes of the apartment's 3D SDF (m).
const SDF_VOXELS_M: [f64; 4] = [0.2, 0.1, 0.05, 0.025];

/// The speed suite's scenarios unless `--scenarios` names others, and its sampling K.
pub(super) const SPEED_SCENARIOS: [&str; 2] = ["moving_obstacle", "circle_4"];
const SPEED_KS: [usize; 4] = [4, 8, 16, 32];

pub(super) fn speed(
    args: &EvalJob,
    c: &SuiteParts,
    scenarios: &[Scenario],
    results: &Path,
) -> Result<()> {
    let controllers = chosen_controllers(NamedController::speed(&SPEED_KS), &args.controllers)?;
    run_rows(
        args,
        c,
        scenarios,
        &controllers,
        results,
        "speed",
        None,
        |_| Ok(()),
    )?;
    // The ray-count knob: each policy on held-out box scenes and crossings.
    box_and_crossing_rows(args, c, &RAYS_POLICIES, &results.join("rays.json"))?;
    // The policy-width knob, the same way.
    box_and_crossing_rows(args, c, &WIDTH_POLICIES, &results.join("width.json"))?;
    let ctx = crate::motion::cvae::BodyContext::new(&c.body, &[])?;
    sdf_rows(args, c, &ctx, results)
}

/// The speed suite's SDF-resolution knob: the shipped policy (mean action) on Table 2's
/// apartment pairs, scene penetration (Eq. 11) measured on 3D SDFs of each voxel size.
fn sdf_rows(
    args: &EvalJob,
    c: &SuiteParts,
    ctx: &crate::motion::cvae::BodyContext,
    results: &Path,
) -> Result<()> {
    use crate::eval::policy_tasks::{evaluate, HeldOutController};
    use crate::motion::cvae::infer::InferBackend;
    use crate::policy::env::EnvParts;
    let t0 = std::time::Instant::now();
    let shipped = crate::policy::weights::SHIPPED_POLICY;
    let config = crate::policy::weights::SHIPPED_POLICY_CONFIG;
    let net = table_policy(c, (shipped, config))?;
    let controller: HeldOutController<InferBackend> = HeldOutController::Policy {
        net: &net,
        mean_action: true,
        spread: 1.0,
    };
    let progress = bar(args, SDF_VOXELS_M.len(), "SDF resolutions");
    let mut rows = Vec::new();
    for voxel_m in SDF_VOXELS_M {
        let built = std::time::Instant::now();
        let fixed = table2_scene(args, voxel_m)?;
        let setup_s = built.elapsed().as_secs_f64();
        let parts = EnvParts {
            model: &c.model,
            body: ctx,
            bank: &c.bank,
            prior: &c.prior,
            fixed: Some(&fixed),
            dwellings: &[],
        };
        let (report, _) = evaluate(
            &parts,
            table2_settings(),
            &controller,
            (args.episodes, 50, args.seed),
            |_| {},
        )?;
        let mut row = PolicyRow::new(
            ("shipped policy", shipped, config),
            &format!("apartment, SDF voxel {voxel_m} m"),
            "mean",
            &report,
            true,
        );
        row.setup_s = Some(setup_s);
        rows.push(row);
        progress.inc(1);
    }
    progress.finish_and_clear();
    write_policy_rows(&results.join("sdf.json"), args, c, t0, rows)
}
