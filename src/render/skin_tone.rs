//! Skin: each agent's body material, drawn per agent from a seed (`[render.skin]`). The tone is
//! one of the ten swatches of the Monk Skin Tone scale (Google, CC BY 4.0; light 1 to dark 10),
//! drawn uniformly from the tones the config allows; the material is procedural — a Principled
//! BSDF with that base colour, faint mottling from a noise texture on the mesh's rest-pose
//! coordinates (so it stays on the skin as the body moves), some subsurface scattering and a
//! skin-like roughness. Where the body model carries MakeHuman's UV layout and its region masks
//! lie beside it (`textures/`), lips, eyelids, ears, areolae and nails are tinted through the
//! masks ([`SKIN_REGIONS`]); bodies are clothing-free. Every choice is in the shard spec and the
//! annotations.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde::{Deserialize, Serialize};

use crate::body::BodyModel;
use crate::math::random::uniform_open01;

/// The Monk Skin Tone scale's swatches, sRGB (8-bit), tone 1 (lightest) to 10 (darkest).
pub(crate) const MONK_SKIN_TONES_SRGB: [[u8; 3]; 10] = [
    [0xf6, 0xed, 0xe4],
    [0xf3, 0xe7, 0xdb],
    [0xf7, 0xea, 0xd0],
    [0xea, 0xda, 0xba],
    [0xd7, 0xbd, 0x96],
    [0xa0, 0x7e, 0x56],
    [0x82, 0x5c, 0x43],
    [0x60, 0x41, 0x34],
    [0x3a, 0x31, 0x2a],
    [0x29, 0x24, 0x20],
];

/// An 8-bit sRGB value as linear light.
pub(crate) fn srgb_to_linear(v: u8) -> f64 {
    crate::math::colour::srgb_to_linear(v as f64 / 255.0)
}

/// One agent's skin material, as Blender receives it.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Skin {
    /// Monk Skin Tone, 1 (lightest) to 10 (darkest).
    pub monk_skin_tone: u8,
    /// Base colour, linear RGB (the swatch through the sRGB transfer function).
    pub base_rgb: [f64; 3],
    /// Relative amplitude of the noise mottling the base colour (0 = flat).
    pub mottle: f64,
    /// Principled BSDF roughness.
    pub roughness: f64,
    /// Principled BSDF subsurface weight (radius: skin's red-scattering default).
    pub subsurface_weight: f64,
}

/// A region of the skin that MakeHuman paints with a grey mask in its UV layout (CC0, from
/// MPFB2), and how egogen colours it: `(1 − mix)·(base ∘ tint) + mix·toward` in linear RGB,
/// with its own roughness. The masks' soft edges blend the region into the skin around it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkinRegion {
    /// The region's name (as recorded in the annotations).
    pub name: &'static str,
    /// Its mask's file name in the body model's `textures/` directory.
    pub mask_file: &'static str,
    /// Per-channel factor on the skin's base colour.
    pub tint: [f64; 3],
    /// How far the tinted colour moves toward `toward` (0 keeps the tint only).
    pub mix: f64,
    /// A colour of its own (linear RGB), for regions paler than any skin (nails).
    pub toward: [f64; 3],
    pub roughness: f64,
}

/// The regions egogen tints: lips redder and darker, eyelids and ears a little flushed, areolae
/// darker, nails paler, pinker and glossier than the skin they sit on, the eyes dark.
pub const SKIN_REGIONS: [SkinRegion; 7] = [
    SkinRegion::tinted("lips", "mpfb_lips.jpg", [0.80, 0.50, 0.50], 0.35),
    SkinRegion::tinted("eyelids", "mpfb_eyelids.jpg", [0.90, 0.78, 0.76], 0.45),
    SkinRegion::tinted("ears", "mpfb_ears.jpg", [1.0, 0.86, 0.84], 0.45),
    SkinRegion::tinted("areolae", "mpfb_aureolae.jpg", [0.62, 0.46, 0.42], 0.45),
    SkinRegion::nail("fingernails", "mpfb_fingernails.jpg"),
    SkinRegion::nail("toenails", "mpfb_toenails.jpg"),
    // The eye sockets (MakeHuman's skins paint them plain red; the body has no eyeballs): a
    // dark, wet eye, 92 % of the way to a dark brown whatever the skin.
    SkinRegion {
        name: "eyes",
        mask_file: "egogen_eyes.jpg",
        tint: [1.0; 3],
        mix: 0.92,
        toward: [0.05, 0.035, 0.03],
        roughness: 0.1,
    },
];

/// The skin detail map's file name in the body model's `textures/`: the relative lightness of
/// MakeHuman's skin albedo (face features, creases, freckles; 0.5 = the skin's mean), built by
/// `tools/build_skin_detail.py`. The skin's colour, regions included, is multiplied by twice it.
pub(crate) const SKIN_DETAIL_FILE: &str = "egogen_skin_detail.jpg";

/// One region as painted on one body: what Blender receives (with its mask) and the
/// annotations record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionPaint {
    pub region: String,
    /// The mask's file name (in the body model's `textures/`).
    pub mask: String,
    /// Linear RGB inside the mask.
    pub rgb: [f64; 3],
    pub roughness: f64,
}

impl SkinRegion {
    /// A region that keeps the skin's colour, tinted.
    const fn tinted(
        name: &'static str,
        mask_file: &'static str,
        tint: [f64; 3],
        roughness: f64,
    ) -> Self {
        Self {
            name,
            mask_file,
            tint,
            mix: 0.0,
            toward: [0.0; 3],
            roughness,
        }
    }

    /// A nail: 45 % of the way from the skin to a pale pink, glossy.
    const fn nail(name: &'static str, mask_file: &'static str) -> Self {
        Self {
            name,
            mask_file,
            tint: [1.0; 3],
            mix: 0.45,
            toward: [0.78, 0.60, 0.55],
            roughness: 0.15,
        }
    }

    /// This region's colour on a skin.
    pub fn paint(&self, skin: &Skin) -> RegionPaint {
        let rgb = std::array::from_fn(|c| {
            (1.0 - self.mix) * skin.base_rgb[c] * self.tint[c] + self.mix * self.toward[c]
        });
        RegionPaint {
            region: self.name.to_owned(),
            mask: self.mask_file.to_owned(),
            rgb,
            roughness: self.roughness,
        }
    }
}

/// How agents' skins are drawn.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SkinPlan {
    /// The Monk tones allowed (1..=10), each drawn with equal probability.
    pub tones: Vec<u8>,
    pub seed: u64,
}

impl Default for SkinPlan {
    /// Every tone, seed 0.
    fn default() -> Self {
        Self {
            tones: (1..=10).collect(),
            seed: 0,
        }
    }
}

impl SkinPlan {
    /// The skin of agent `index` (the same agent, seed and tones give the same skin).
    pub(crate) fn draw(&self, index: usize) -> Skin {
        let mut rng = ChaCha8Rng::seed_from_u64(
            self.seed.rotate_left(17) ^ (index as u64 + 1).wrapping_mul(0xD1B5_4A32_D192_ED03),
        );
        let k = (uniform_open01(&mut rng) * self.tones.len() as f64) as usize;
        let tone = self.tones[k.min(self.tones.len() - 1)];
        let swatch = MONK_SKIN_TONES_SRGB[(tone as usize).clamp(1, 10) - 1];
        Skin {
            monk_skin_tone: tone,
            base_rgb: swatch.map(srgb_to_linear),
            mottle: 0.08,
            roughness: 0.45,
            subsurface_weight: 0.15,
        }
    }
}

/// What is painted on a body model's skin from the `textures/` beside it: the regions' masks
/// (all or none) and, with them, the detail map. Both are in the model's UV layout, so Blender
/// needs its UVs only when there are masks.
#[derive(Debug, Clone)]
pub(crate) struct SkinTextures {
    pub(crate) masks: Vec<(SkinRegion, PathBuf)>,
    pub(crate) detail: Option<PathBuf>,
}

impl SkinTextures {
    /// The textures beside `model` (none for a model without UVs or masks).
    pub(crate) fn of(model: &BodyModel) -> Result<Self> {
        let masks = skin_region_masks(model)?;
        let detail = match masks.is_empty() {
            true => None,
            false => skin_detail_map(model)?,
        };
        Ok(Self { masks, detail })
    }

    /// Whether Blender needs the body's UVs to paint them.
    pub(crate) fn need_uvs(&self) -> bool {
        !self.masks.is_empty()
    }
}

/// `textures/` beside a body model with UVs (what is painted there is in its UV layout).
fn body_textures(model: &BodyModel) -> Option<PathBuf> {
    match (&model.uvs, model.source.parent()) {
        (Some(_), Some(parent)) => Some(parent.join("textures")),
        _ => None,
    }
}

/// The skin detail map beside a body model that has region masks, when it is there
/// ([`SKIN_DETAIL_FILE`]).
fn skin_detail_map(model: &BodyModel) -> Result<Option<PathBuf>> {
    let Some(path) = body_textures(model).map(|d| d.join(SKIN_DETAIL_FILE)) else {
        return Ok(None);
    };
    if !path.is_file() {
        return Ok(None);
    }
    Ok(Some(std::fs::canonicalize(&path).with_context(|| {
        format!("resolving {}", path.display())
    })?))
}

/// The skin regions' masks for `model`: in `textures/` beside the model file, painted in the
/// UV layout the model carries (ours: MakeHuman's). None when the model has no UVs or no masks
/// lie beside it (the official SMPL-X files: another layout); all of them, or an error naming
/// the first one missing.
fn skin_region_masks(model: &BodyModel) -> Result<Vec<(SkinRegion, PathBuf)>> {
    let Some(dir) = body_textures(model) else {
        return Ok(Vec::new());
    };
    let masks: Vec<(SkinRegion, PathBuf)> = SKIN_REGIONS
        .iter()
        .map(|r| (*r, dir.join(r.mask_file)))
        .collect();
    let present = masks.iter().filter(|(_, p)| p.is_file()).count();
    if present == 0 {
        return Ok(Vec::new());
    }
    if let Some((region, path)) = masks.iter().find(|(_, p)| !p.is_file()) {
        bail!(
            "{}: the skin region mask for `{}` is missing ({present} of {} masks are there); \
             masks beside a body model are used all together",
            path.display(),
            region.name,
            masks.len()
        );
    }
    masks
        .into_iter()
        .map(|(r, p)| {
            let p =
                std::fs::canonicalize(&p).with_context(|| format!("resolving {}", p.display()))?;
            Ok((r, p))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::BodyModel;

    #[test]
    fn tones_run_light_to_dark_and_draws_cover_them() {
        let luminance = |t: usize| {
            let [r, g, b] = MONK_SKIN_TONES_SRGB[t].map(srgb_to_linear);
            0.2126 * r + 0.7152 * g + 0.0722 * b
        };
        assert!((1..10).all(|t| luminance(t) <= luminance(t - 1) + 0.03));
        assert!(luminance(0) > 10.0 * luminance(9));
        let plan = SkinPlan::default();
        let mut seen = [0usize; 10];
        for i in 0..2000 {
            seen[plan.draw(i).monk_skin_tone as usize - 1] += 1;
        }
        // Uniform: 200 each, ±5σ.
        assert!(seen.iter().all(|&n| (130..=270).contains(&n)), "{seen:?}");
        assert_eq!(plan.draw(3), plan.draw(3));
        let dark = SkinPlan {
            tones: vec![9, 10],
            seed: 1,
        };
        assert!((0..50).all(|i| dark.draw(i).monk_skin_tone >= 9));
    }

    #[test]
    fn regions_keep_their_skin_s_tone_order_and_nails_stay_pale() {
        let skins: Vec<Skin> = (1..=10)
            .map(|t| {
                SkinPlan {
                    tones: vec![t],
                    seed: 0,
                }
                .draw(0)
            })
            .collect();
        let lum = |c: [f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        for region in SKIN_REGIONS {
            let paints: Vec<RegionPaint> = skins.iter().map(|s| region.paint(s)).collect();
            for (skin, paint) in skins.iter().zip(&paints) {
                assert!(
                    paint.rgb.iter().all(|c| (0.0..=1.0).contains(c)),
                    "{paint:?}"
                );
                if region.mix == 0.0 {
                    // A tint never lightens: lips and areolae are darker than the skin.
                    assert!(lum(paint.rgb) <= lum(skin.base_rgb) + 1e-12, "{paint:?}");
                }
            }
            // Lighter skin, lighter region.
            assert!(paints
                .windows(2)
                .all(|w| lum(w[1].rgb) <= lum(w[0].rgb) + 0.03));
        }
        let nails = SKIN_REGIONS
            .iter()
            .find(|r| r.name == "fingernails")
            .unwrap();
        let darkest = &skins[9];
        assert!(lum(nails.paint(darkest).rgb) > 2.0 * lum(darkest.base_rgb));
    }

    #[test]
    fn skin_masks_are_used_all_together_beside_a_model_with_uvs() {
        let root = crate::paths::crate_root();
        let shipped = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
        let masks = skin_region_masks(&shipped).unwrap();
        assert_eq!(masks.len(), SKIN_REGIONS.len());
        assert!(masks.iter().all(|(_, p)| p.is_absolute() && p.is_file()));
        // The detail map ships beside them.
        let detail = skin_detail_map(&shipped).unwrap().unwrap();
        assert!(detail.is_absolute() && detail.ends_with(SKIN_DETAIL_FILE));

        // The same model in a directory without masks: no regions.
        let dir = tempfile::tempdir().unwrap();
        let mut elsewhere = shipped.clone();
        elsewhere.source = dir.path().join("SMPLX_NEUTRAL.npz");
        assert!(skin_region_masks(&elsewhere).unwrap().is_empty());
        assert_eq!(skin_detail_map(&elsewhere).unwrap(), None);
        // Some of them: an error naming the first one missing.
        let textures = dir.path().join("textures");
        std::fs::create_dir(&textures).unwrap();
        std::fs::copy(
            root.join("assets/body/textures/mpfb_lips.jpg"),
            textures.join("mpfb_lips.jpg"),
        )
        .unwrap();
        let msg = format!("{:#}", skin_region_masks(&elsewhere).unwrap_err());
        assert!(
            msg.contains("mpfb_eyelids.jpg") && msg.contains("`eyelids`") && msg.contains("1 of 7"),
            "{msg}"
        );
        // A model without UVs never looks for them.
        elsewhere.uvs = None;
        assert!(skin_region_masks(&elsewhere).unwrap().is_empty());
    }
}
