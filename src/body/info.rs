//! `egogen body info`: a body model summarised (sizes, rest stature, CPF calibration).

use std::path::Path;

use anyhow::Result;

use crate::body::{BodyModel, CpfCalibration};
use crate::math::Vec3;

/// Prints the model's sizes, rest stature and CPF calibration.
pub(crate) fn body_info(model: &Path) -> Result<()> {
    let m = BodyModel::load(model)?;
    let shaped = m.shape(&[], &[])?;
    let cal = CpfCalibration::from_rest_joints(&shaped.rest_joints);
    let (lo, hi) = shaped.v_shaped.iter().fold(
        (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    );
    println!("model:            {}", m.source.display());
    println!("vertices:         {}", m.num_vertices());
    println!("triangles:        {}", m.faces.len());
    println!("betas:            {}", m.num_betas());
    println!("expression:       {}", m.num_expression());
    println!(
        "pose correctives: {}",
        if m.has_pose_correctives() {
            "yes"
        } else {
            "none (skipped)"
        }
    );
    println!("stature (rest):   {:.3} m", hi.y - lo.y);
    let eyes = (shaped.rest_joints[23] + shaped.rest_joints[24]) * 0.5;
    println!(
        "CPF at rest:      ({:.3}, {:.3}, {:.3}) m; eye-bone plane tilt removed: {:.1}°",
        eyes.x,
        eyes.y,
        eyes.z,
        cal.rest_tilt_down_rad().to_degrees()
    );
    Ok(())
}
