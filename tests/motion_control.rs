//! The shipped training config's primitives walk at a human pace, and whole clips are held
//! out (it reads the config as `egogen train primitive` does; motion control's other tests are
//! `motion::cvae::control_tests`, in the crate).

mod common;

use egogen::body::BodyModel;
use egogen::motion::cvae::pace::{set_paces, PaceSummary};
use egogen::motion::cvae::tensor_body::{RigGeometry, TensorRig};
use egogen::motion::cvae::train::evaluation_sets;

#[test]
fn shipped_training_primitives_walk_at_a_human_pace() {
    let plan = egogen::cli::train_primitive::load_train_plan(
        &common::repo_root().join("configs/train_primitive.toml"),
    )
    .unwrap();
    let body = BodyModel::load(&plan.body_model).unwrap();
    let (train, held) = evaluation_sets(&plan, &body, true).unwrap();
    assert!(
        train.len() > 4000 && held.len() > 400,
        "{} / {}",
        train.len(),
        held.len()
    );
    let rig = TensorRig::<egogen::motion::cvae::infer::InferBackend>::new(
        &RigGeometry::new(&body, &[]).unwrap(),
        &Default::default(),
    );
    let s = PaceSummary::of(&set_paces(&rig, &train, 512));
    assert!(
        (0.9..1.5).contains(&s.speed_m_s.p50) && s.share_walking > 0.7,
        "{s:?}"
    );
    // Whole clips are held out: none of the held-out clips is also trained on.
    let held_paths: Vec<_> = plan
        .clips
        .iter()
        .filter(|c| c.held_out)
        .map(|c| &c.path)
        .collect();
    assert!(held_paths.len() >= 8);
}
