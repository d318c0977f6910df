//! `egogen body info|shapes|pose|preview|hands`: thin calls into the jobs: a body model
//! summarised (`body::info`), posed to OBJ from a motion file or the scripted walk
//! (`motion::jobs`), drawn along one beta, previewed at rest and walking, and its hands drawn
//! doing each thing a hand does (`synth::body_pictures`).

use std::path::Path;

use anyhow::Result;

/// Prints the model's sizes, rest stature and CPF calibration.
pub fn body_info(model: &Path) -> Result<()> {
    crate::body::info::body_info(model)
}

/// Draws the rest body for each of `values` of beta `beta`, side by side, to `out` (PNG).
pub fn body_shapes(model: &Path, beta: usize, values: &[f64], out: &Path) -> Result<()> {
    crate::synth::body_pictures::body_shapes(model, beta, values, out)
}

/// Poses frame `frame` of `motion` (or of the scripted walk at 40 fps) and writes it as OBJ.
pub fn body_pose(model: &Path, motion: Option<&Path>, frame: usize, out: &Path) -> Result<()> {
    crate::motion::jobs::body_pose(model, motion, frame, out)
}

/// The body with `betas` at rest (front, side) and mid-stride (front, side), to `out` (PNG).
pub fn body_preview(model: &Path, betas: &[f64], out: &Path, height_px: usize) -> Result<()> {
    crate::synth::body_pictures::body_preview(model, betas, out, height_px)
}

/// The right hand of `people` people doing each thing a hand does, seen from the thumb's side
/// and from the palm, to `out` (PNG).
pub fn body_hands(model: &Path, people: usize, out: &Path, cell_px: usize) -> Result<()> {
    crate::synth::body_pictures::body_hands(model, people, out, cell_px)
}
