//! Outfits: each person's clothes, socks, shoes and hair, drawn from a seed (`[render.outfits]`)
//! and painted on the body's own surface — no cloth mesh, the skinning stays clothing-free.
//! A drawn [`Outfit`] is a set of garments (a top, a bottom or a dress, socks, shoes, hair),
//! each with its cut (where a sleeve or hem ends, as a share of the person's own bone lengths),
//! its fabric, pattern and colours. [`regions`] turns a cut into one signed distance per vertex
//! and garment on the person's shaped rest body (positive on the garment), which Blender
//! thresholds per pixel and fills with a procedural fabric (`render_shard.py`); a body's
//! [`ShardOutfit`] carries both to Blender. Everything drawn is in the shard spec and the
//! annotations; `mode = "off"` draws nothing and leaves the
//! files as they were before outfits.

pub(crate) mod regions;

use std::collections::BTreeMap;
use std::path::PathBuf;

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde::{Deserialize, Serialize};

use crate::math::colour::hsv_linear;
use crate::math::random::{uniform_in, uniform_open01, weighted_index};

/// `[render.outfits] mode`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum OutfitsMode {
    /// Every person dressed (the default).
    #[default]
    On,
    /// Bare bodies: the files as before outfits existed.
    Off,
}

/// Names the styles of one kind of garment, for config tables and the annotations.
pub(crate) trait Style: Copy + 'static {
    const ALL: &'static [Self];
    fn name(self) -> &'static str;
}

macro_rules! styles {
    ($(#[$doc:meta])* $ty:ident { $($variant:ident => $name:literal),+ $(,)? }) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
        pub(crate) enum $ty { $(#[serde(rename = $name)] $variant),+ }
        impl Style for $ty {
            const ALL: &'static [Self] = &[$(Self::$variant),+];
            fn name(self) -> &'static str {
                match self { $(Self::$variant => $name),+ }
            }
        }
    };
}

styles!(
    /// What a top's sleeves are.
    TopStyle { Sleeveless => "sleeveless", ShortSleeves => "short_sleeves", LongSleeves => "long_sleeves" }
);
styles!(
    /// What is worn below the waist (a dress is a top and a skirt of one fabric).
    BottomStyle { Shorts => "shorts", Knee => "knee", Trousers => "trousers", Skirt => "skirt", Dress => "dress" }
);
styles!(
    /// Hair painted on the scalp (`buzz`: cropped to stubble; `none`: bald).
    HairStyle { None => "none", Buzz => "buzz", Short => "short", Bob => "bob", Long => "long" }
);
styles!(
    /// A top's neckline.
    Neckline { Crew => "crew", Scoop => "scoop", V => "v" }
);
styles!(
    /// What a garment is made of (sets its weave drawing, roughness and sheen).
    Fabric { Cotton => "cotton", Denim => "denim", Knit => "knit", Wool => "wool", Leather => "leather", Synthetic => "synthetic" }
);
styles!(
    /// What is printed or woven on a fabric.
    Pattern { Plain => "plain", Stripes => "stripes", Checks => "checks", Print => "print" }
);

/// The share of people in each style of one garment, indexed as `S::ALL`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Shares<S: Style> {
    pub(crate) weights: Vec<f64>,
    _style: std::marker::PhantomData<S>,
}

impl<S: Style> Shares<S> {
    pub(crate) fn new(weights: Vec<f64>) -> Self {
        assert_eq!(weights.len(), S::ALL.len());
        Self {
            weights,
            _style: std::marker::PhantomData,
        }
    }

    /// Shares from a config table `{ style = weight, … }` (styles left out weigh 0); an error
    /// names the style or weight that is wrong.
    pub(crate) fn from_table(table: &BTreeMap<String, f64>) -> Result<Self, String> {
        let mut weights = vec![0.0; S::ALL.len()];
        for (name, &w) in table {
            let Some(k) = S::ALL.iter().position(|s| s.name() == name) else {
                let known: Vec<&str> = S::ALL.iter().map(|s| s.name()).collect();
                return Err(format!(
                    "unknown style `{name}`; expected any of {}",
                    known.join(", ")
                ));
            };
            if !(w.is_finite() && w >= 0.0) {
                return Err(format!("`{name}`: expected a share ≥ 0, found {w}"));
            }
            weights[k] = w;
        }
        if weights.iter().sum::<f64>() <= 0.0 {
            return Err("expected at least one style with a share above 0".into());
        }
        Ok(Self::new(weights))
    }

    fn draw(&self, rng: &mut ChaCha8Rng) -> S {
        S::ALL[weighted_index(rng, self.weights.iter().copied())]
    }
}

impl<S: Style> Serialize for Shares<S> {
    fn serialize<Ser: serde::Serializer>(&self, s: Ser) -> Result<Ser::Ok, Ser::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(S::ALL.len()))?;
        for (style, w) in S::ALL.iter().zip(&self.weights) {
            map.serialize_entry(style.name(), w)?;
        }
        map.end()
    }
}

/// How people's outfits are drawn.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct OutfitPlan {
    pub(crate) mode: OutfitsMode,
    pub(crate) seed: u64,
    pub(crate) tops: Shares<TopStyle>,
    pub(crate) bottoms: Shares<BottomStyle>,
    pub(crate) hair: Shares<HairStyle>,
    /// The share of people wearing shoes (the others are barefoot or in socks).
    pub(crate) shoes: f64,
    /// `[MIN, MAX]` saturation of the garments' colours (HSV, sRGB).
    pub(crate) saturation: [f64; 2],
    /// `[MIN, MAX]` value (brightness) of the garments' colours (HSV, sRGB).
    pub(crate) value: [f64; 2],
}

impl Default for OutfitPlan {
    /// Dressed, seed 0: trousers more often than not, most people with shoes and short hair,
    /// colours from greys and muted tones to bright ones.
    fn default() -> Self {
        Self {
            mode: OutfitsMode::On,
            seed: 0,
            tops: Shares::new(vec![1.0, 3.0, 3.0]),
            bottoms: Shares::new(vec![1.5, 1.0, 4.0, 1.0, 1.0]),
            hair: Shares::new(vec![0.7, 0.8, 4.0, 2.0, 2.5]),
            shoes: 0.9,
            saturation: [0.0, 0.75],
            value: [0.12, 0.92],
        }
    }
}

/// One garment as drawn: what Blender paints and the annotations record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Garment {
    /// `top`, `bottom`, `socks`, `shoes` or `hair`: the column of its region in the fields.
    pub(crate) slot: String,
    /// Its style (`long_sleeves`, `trousers`, `bob`, …).
    pub(crate) style: String,
    pub(crate) fabric: Fabric,
    pub(crate) pattern: Pattern,
    /// Linear RGB.
    pub(crate) base_rgb: [f64; 3],
    /// The pattern's second colour (linear RGB).
    pub(crate) accent_rgb: [f64; 3],
    /// The pattern's size (m: a stripe's period, a check's side, a print's motif).
    pub(crate) scale_m: f64,
    pub(crate) roughness: f64,
    /// Principled BSDF sheen weight (soft fabrics' grazing glow).
    pub(crate) sheen: f64,
    /// How much of the skin it hides (1; a buzz cut's stubble 0.5).
    pub(crate) cover: f64,
}

/// Where each garment ends, in shares of the person's own lengths (so one cut fits any shape;
/// [`regions`] turns it into metres on a body).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Cut {
    /// A sleeve's end, as a share of the shoulder-to-wrist length (0: at the shoulder joint).
    pub(crate) sleeve: f64,
    pub(crate) neckline: Neckline,
    /// The neckline's depth below the neck's base, as a share of the neck-to-pelvis length.
    pub(crate) neck_depth: f64,
    /// The top's hem, above the pelvis joint, as a share of the neck-to-pelvis length.
    pub(crate) hem: f64,
    /// The bottom's waistband, likewise.
    pub(crate) waist: f64,
    /// The bottom's leg end, as a share of the hip-to-ankle length.
    pub(crate) leg: f64,
    /// The socks' top, above the ankle joint, as a share of the ankle-to-knee length.
    pub(crate) socks: f64,
    /// The shoes' top, likewise (below 0: below the ankle joint).
    pub(crate) shoes: f64,
    /// The hairline above the eyes at the front, side and back, in head heights (eyes to
    /// crown; negative: below the eyes).
    pub(crate) hairline: [f64; 3],
}

/// One person's outfit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Outfit {
    /// Drawn from the lowest layer up: each covers those before it where they overlap.
    pub(crate) garments: Vec<Garment>,
    /// The top tucked into the bottom (bottom drawn over it) or worn over it.
    pub(crate) tucked: bool,
    pub(crate) cut: Cut,
}

/// A person's outfit as Blender paints it: the garments, lowest layer first, and per vertex
/// each slot's signed distance and the rest position (float32 N×8,
/// [`regions::garment_fields`]).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardOutfit {
    pub(crate) fields_npy: PathBuf,
    /// The slots in the fields' column order.
    pub(crate) slots: Vec<String>,
    pub(crate) outfit: Outfit,
}

/// The regions' columns in the per-vertex fields ([`regions::garment_fields`]); a slot's
/// place + 1 is its code in the frame file's `segmentation.garment` (0: the skin).
pub(crate) const SLOTS: [&str; 5] = ["top", "bottom", "socks", "shoes", "hair"];

impl OutfitPlan {
    /// The outfit of person `index` (the same person, seed and plan give the same outfit);
    /// `None` when outfits are off.
    pub(crate) fn draw(&self, index: usize) -> Option<Outfit> {
        if self.mode == OutfitsMode::Off {
            return None;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(
            self.seed.rotate_left(29) ^ (index as u64 + 1).wrapping_mul(0xA24B_AED4_963E_E407),
        );
        let rng = &mut rng;
        let top = self.tops.draw(rng);
        let bottom = self.bottoms.draw(rng);
        let hair = self.hair.draw(rng);
        let dress = bottom == BottomStyle::Dress;
        let neckline = Neckline::ALL[(uniform_open01(rng) * 3.0) as usize % 3];
        let sleeve = match top {
            TopStyle::Sleeveless => uniform_in(rng, -0.02, 0.04),
            TopStyle::ShortSleeves => uniform_in(rng, 0.22, 0.42),
            TopStyle::LongSleeves => uniform_in(rng, 0.9, 0.98),
        };
        let neck_depth = match neckline {
            Neckline::Crew => uniform_in(rng, 0.0, 0.04),
            Neckline::Scoop => uniform_in(rng, 0.12, 0.22),
            Neckline::V => uniform_in(rng, 0.16, 0.3),
        };
        let waist = uniform_in(rng, 0.05, 0.2);
        let tucked = !dress && uniform_open01(rng) < 0.3;
        // A dress's top ends where its skirt begins; a top worn over the bottom reaches
        // below the waistband.
        let hem = if dress || tucked {
            waist - 0.03
        } else {
            uniform_in(rng, -0.16, 0.0)
        };
        let leg = match bottom {
            BottomStyle::Shorts => uniform_in(rng, 0.22, 0.4),
            BottomStyle::Knee => uniform_in(rng, 0.52, 0.66),
            BottomStyle::Trousers => uniform_in(rng, 0.96, 1.02),
            BottomStyle::Skirt | BottomStyle::Dress => uniform_in(rng, 0.3, 0.62),
        };
        let shod = uniform_open01(rng) < self.shoes;
        let socked = uniform_open01(rng) < if shod { 0.85 } else { 0.4 };
        let socks = uniform_in(rng, 0.1, 0.6);
        let boots = uniform_open01(rng) < 0.2;
        let shoes = if boots {
            uniform_in(rng, 0.15, 0.35)
        } else {
            uniform_in(rng, -0.12, 0.02)
        };
        let hairline = match hair {
            HairStyle::None => [0.0; 3],
            HairStyle::Buzz | HairStyle::Short => [
                uniform_in(rng, 0.42, 0.6),
                uniform_in(rng, 0.05, 0.3),
                uniform_in(rng, -0.95, -0.7),
            ],
            HairStyle::Bob => [
                uniform_in(rng, 0.3, 0.55),
                uniform_in(rng, -0.9, -0.5),
                uniform_in(rng, -1.6, -1.1),
            ],
            HairStyle::Long => [
                uniform_in(rng, 0.3, 0.55),
                uniform_in(rng, -1.3, -0.8),
                uniform_in(rng, -3.5, -2.0),
            ],
        };
        let mut garments = Vec::new();
        let top_garment = self.garment(rng, "top", top.name(), &TOP_FABRICS);
        let bottom_garment = if dress {
            Garment {
                slot: "bottom".into(),
                style: bottom.name().into(),
                ..top_garment.clone()
            }
        } else {
            let fabrics: &[(Fabric, f64)] = match bottom {
                BottomStyle::Skirt => &SKIRT_FABRICS,
                _ => &BOTTOM_FABRICS,
            };
            self.garment(rng, "bottom", bottom.name(), fabrics)
        };
        let top_garment = match dress {
            true => Garment {
                style: "dress".into(),
                ..top_garment
            },
            false => top_garment,
        };
        // Socks lowest (trousers cover them), then the top and bottom in the order worn.
        let socks_garment = self.garment(rng, "socks", "socks", &[(Fabric::Knit, 1.0)]);
        if socked {
            garments.push(socks_garment);
        }
        if tucked {
            garments.extend([top_garment, bottom_garment]);
        } else {
            garments.extend([bottom_garment, top_garment]);
        }
        let shoe_garment = self.shoe(rng, if boots { "boots" } else { "shoes" });
        if shod {
            garments.push(shoe_garment);
        }
        if hair != HairStyle::None {
            garments.push(hair_garment(rng, hair));
        }
        Some(Outfit {
            garments,
            tucked,
            cut: Cut {
                sleeve,
                neckline,
                neck_depth,
                hem,
                waist,
                leg,
                socks,
                shoes,
                hairline,
            },
        })
    }

    /// A garment of one of `fabrics` (with their weights), its pattern and colours.
    fn garment(
        &self,
        rng: &mut ChaCha8Rng,
        slot: &'static str,
        style: &'static str,
        fabrics: &[(Fabric, f64)],
    ) -> Garment {
        let fabric = fabrics[weighted_index(rng, fabrics.iter().map(|f| f.1))].0;
        let pattern = match (fabric, uniform_open01(rng)) {
            (Fabric::Denim | Fabric::Leather, _) => Pattern::Plain,
            (_, u) if u < 0.6 => Pattern::Plain,
            (_, u) if u < 0.75 => Pattern::Stripes,
            (_, u) if u < 0.88 => Pattern::Checks,
            _ => Pattern::Print,
        };
        let base_rgb = match fabric {
            // Denim: indigo, washed from dark to pale, or black.
            Fabric::Denim => hsv_linear(
                uniform_in(rng, 212.0, 228.0),
                uniform_in(rng, 0.35, 0.7),
                uniform_in(rng, 0.2, 0.65),
            ),
            Fabric::Leather => hsv_linear(
                uniform_in(rng, 15.0, 35.0),
                uniform_in(rng, 0.2, 0.7),
                uniform_in(rng, 0.08, 0.45),
            ),
            _ => self.colour(rng),
        };
        let accent_rgb = match pattern {
            Pattern::Plain => base_rgb.map(|c| c * uniform_in(rng, 0.75, 0.9)),
            _ => self.colour(rng),
        };
        let (roughness, sheen) = match fabric {
            Fabric::Cotton => (0.8, 0.3),
            Fabric::Denim => (0.85, 0.2),
            Fabric::Knit => (0.9, 0.5),
            Fabric::Wool => (0.95, 0.7),
            Fabric::Leather => (0.45, 0.0),
            Fabric::Synthetic => (0.4, 0.15),
        };
        let scale_m = match pattern {
            Pattern::Plain => 0.004,
            Pattern::Stripes => uniform_in(rng, 0.01, 0.06),
            Pattern::Checks => uniform_in(rng, 0.02, 0.08),
            Pattern::Print => uniform_in(rng, 0.02, 0.07),
        };
        Garment {
            slot: slot.into(),
            style: style.into(),
            fabric,
            pattern,
            base_rgb,
            accent_rgb,
            scale_m,
            roughness,
            sheen,
            cover: 1.0,
        }
    }

    /// A garment colour: any hue, the plan's saturation and value.
    fn colour(&self, rng: &mut ChaCha8Rng) -> [f64; 3] {
        hsv_linear(
            uniform_in(rng, 0.0, 360.0),
            uniform_in(rng, self.saturation[0], self.saturation[1]),
            uniform_in(rng, self.value[0], self.value[1]),
        )
    }

    /// Shoes or boots: leather or synthetic, mostly dark, sometimes white.
    fn shoe(&self, rng: &mut ChaCha8Rng, style: &'static str) -> Garment {
        let mut g = self.garment(
            rng,
            "shoes",
            style,
            &[(Fabric::Leather, 1.0), (Fabric::Synthetic, 1.0)],
        );
        g.pattern = Pattern::Plain;
        if g.fabric == Fabric::Synthetic {
            let v = if uniform_open01(rng) < 0.3 {
                uniform_in(rng, 0.8, 0.95)
            } else {
                uniform_in(rng, 0.05, 0.4)
            };
            g.base_rgb = hsv_linear(uniform_in(rng, 0.0, 360.0), uniform_in(rng, 0.0, 0.3), v);
        }
        g.accent_rgb = g.base_rgb.map(|c| c * 0.7);
        g
    }
}

const TOP_FABRICS: [(Fabric, f64); 4] = [
    (Fabric::Cotton, 4.0),
    (Fabric::Knit, 1.5),
    (Fabric::Wool, 1.0),
    (Fabric::Synthetic, 1.5),
];
const BOTTOM_FABRICS: [(Fabric, f64); 4] = [
    (Fabric::Denim, 4.0),
    (Fabric::Cotton, 2.0),
    (Fabric::Wool, 1.0),
    (Fabric::Synthetic, 1.0),
];
const SKIRT_FABRICS: [(Fabric, f64); 4] = [
    (Fabric::Cotton, 2.0),
    (Fabric::Denim, 1.0),
    (Fabric::Wool, 1.0),
    (Fabric::Synthetic, 1.0),
];

/// Hair of a natural colour (black, browns, auburn, blond, grey), drawn along its strands.
fn hair_garment(rng: &mut ChaCha8Rng, style: HairStyle) -> Garment {
    // (hue, saturation, value) ranges of natural hair, sRGB.
    const COLOURS: [([f64; 2], [f64; 2], [f64; 2], f64); 6] = [
        ([20.0, 30.0], [0.2, 0.5], [0.04, 0.12], 4.0),  // black
        ([20.0, 32.0], [0.4, 0.7], [0.12, 0.3], 4.0),   // dark brown
        ([25.0, 35.0], [0.4, 0.65], [0.3, 0.5], 2.0),   // brown
        ([12.0, 22.0], [0.6, 0.8], [0.3, 0.55], 0.6),   // auburn
        ([35.0, 45.0], [0.35, 0.6], [0.55, 0.85], 1.2), // blond
        ([30.0, 40.0], [0.0, 0.1], [0.45, 0.8], 0.8),   // grey
    ];
    let pick = COLOURS[weighted_index(rng, COLOURS.iter().map(|c| c.3))];
    let base_rgb = hsv_linear(
        uniform_in(rng, pick.0[0], pick.0[1]),
        uniform_in(rng, pick.1[0], pick.1[1]),
        uniform_in(rng, pick.2[0], pick.2[1]),
    );
    Garment {
        slot: "hair".into(),
        style: style.name().into(),
        fabric: Fabric::Synthetic,
        pattern: Pattern::Stripes,
        base_rgb,
        accent_rgb: base_rgb.map(|c| c * 0.55),
        scale_m: 0.0015,
        roughness: 0.35,
        sheen: 0.6,
        cover: if style == HairStyle::Buzz { 0.5 } else { 1.0 },
    }
}

#[cfg(test)]
mod tests;
