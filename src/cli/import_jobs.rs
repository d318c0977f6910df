//! `egogen motion import`: a CMU BVH clip (or a DeepMimic motion file) imported
//! (`motion::clip_import`), with an optional strip of the source skeleton above the retargeted
//! body (`synth::body_pictures::import_strip`).

use std::path::Path;

use anyhow::Result;

/// Imports `bvh` into `out` at `rate_hz` with the body model at `model`; `mirror` writes
/// `<out>_mirror.npz` too; `strip` a PNG of `strip_frames` columns; the first `skip_frames`
/// source frames are dropped.
#[allow(clippy::too_many_arguments)]
pub(crate) fn import_bvh(
    bvh: &Path,
    out: &Path,
    model: &Path,
    rate_hz: f64,
    mirror: bool,
    strip: Option<&Path>,
    strip_frames: usize,
    skip_frames: usize,
) -> Result<()> {
    let imported = crate::motion::clip_import::import_bvh(
        bvh,
        out,
        model,
        rate_hz,
        mirror,
        strip,
        skip_frames,
    )?;
    if let Some(strip) = strip {
        crate::synth::body_pictures::import_strip(&imported, rate_hz, strip_frames, strip)?;
    }
    Ok(())
}
