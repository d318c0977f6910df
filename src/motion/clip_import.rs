//! `egogen motion import`: a CMU BVH clip (or a DeepMimic motion file) retargeted to the body
//! model, resampled, written as an AMASS-style npz (and its mirror); what it was made from is
//! handed back for the strip picture (`synth::body_pictures::import_strip`).

use std::path::Path;

use anyhow::{bail, Result};

use crate::atomic_file::refuse_existing;
use crate::body::BodyModel;
use crate::motion::bvh::BvhClip;
use crate::motion::MotionSequence;

/// An imported clip: the source skeleton's clip (none for a DeepMimic file), the written
/// sequence and the body model it was retargeted to.
pub(crate) struct ImportedClip {
    pub(crate) clip: Option<BvhClip>,
    pub(crate) seq: MotionSequence,
    pub(crate) model: BodyModel,
}

/// Imports `bvh` into `out` at `rate_hz` with the body model at `model`; `mirror` writes
/// `<out>_mirror.npz` too; `strip`, the strip picture's file, is refused if it exists; the
/// first `skip_frames` source frames are dropped.
pub(crate) fn import_bvh(
    bvh: &Path,
    out: &Path,
    model: &Path,
    rate_hz: f64,
    mirror: bool,
    strip: Option<&Path>,
    skip_frames: usize,
) -> Result<ImportedClip> {
    use crate::motion::resample::{mirror as mirror_seq, resample};
    use crate::motion::retarget::retarget_cmu;

    refuse_existing(out)?;
    let mirror_path = out.with_file_name(format!(
        "{}_mirror.npz",
        out.file_stem().unwrap_or_default().to_string_lossy()
    ));
    if mirror {
        refuse_existing(&mirror_path)?;
    }
    if let Some(s) = strip {
        refuse_existing(s)?;
    }
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        bail!("--rate-hz must be positive, got {rate_hz}");
    }
    let m = BodyModel::load(model)?;
    let is_bvh = bvh
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bvh"));
    let (clip, mut full) = if is_bvh {
        let mut clip = BvhClip::read(bvh)?;
        if skip_frames >= clip.frames.len() {
            bail!(
                "--skip-frames {skip_frames}: {} has only {} frames",
                bvh.display(),
                clip.frames.len()
            );
        }
        clip.frames.drain(..skip_frames);
        let seq = retarget_cmu(&clip, &m)?;
        (Some(clip), seq)
    } else {
        let mut seq = crate::motion::deepmimic::import_deepmimic(bvh, &m)?;
        if skip_frames >= seq.len() {
            bail!(
                "--skip-frames {skip_frames}: {} has only {} frames",
                bvh.display(),
                seq.len()
            );
        }
        seq.poses.drain(..skip_frames);
        seq.trans.drain(..skip_frames);
        (None, seq)
    };
    full.gender = "neutral".into();
    let seq = resample(&full, rate_hz);
    seq.write_amass(out)?;
    println!(
        "wrote {} ({} frames at {} Hz from {} at {} Hz)",
        out.display(),
        seq.len(),
        rate_hz,
        bvh.display(),
        full.frame_rate_hz
    );
    if mirror {
        mirror_seq(&seq, &m)?.write_amass(&mirror_path)?;
        println!("wrote {}", mirror_path.display());
    }
    Ok(ImportedClip {
        clip,
        seq,
        model: m,
    })
}
