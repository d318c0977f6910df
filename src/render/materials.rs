//! Materials drawn per take for the scene's surfaces (`[render.materials]`): what each object
//! is (a floor, a wall, a ceiling or furniture — by its [`crate::scene::ObjectClass`] where its
//! name or label says, by its
//! surfaces' orientation otherwise), which procedural pattern it gets (floors: wood planks,
//! tiles, carpet, stone; walls: plaster, paint, wallpaper, brick; ceilings: plaster; furniture: wood,
//! fabric, leather, metal, plastic) and that pattern's colours, scale and roughness, drawn per
//! object from a seed. Blender builds each from shader nodes only (no image files;
//! `blender_scripts/render_shard.py`), replacing the object's own materials (never those that
//! let light through: the depth would change). Modes: `keep` (the
//! scene's own; the default), `fill` (only objects without a texture of their own) and `all`.
//! Every choice is in the shard spec and the annotations.

use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde::{Deserialize, Serialize};

use crate::math::colour::hsv_linear;
use crate::math::random::{uniform_in, weighted_index};
use crate::scene::ObjectClass;

/// Which objects get a drawn material (`[render.materials] mode`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MaterialsMode {
    /// None: every object keeps the scene's own materials.
    #[default]
    Keep,
    /// Objects without an image texture or vertex colours of their own.
    Fill,
    /// Every object egogen can class (plants and small things keep theirs).
    All,
}

/// How a take's materials are drawn.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct MaterialsPlan {
    pub mode: MaterialsMode,
    pub seed: u64,
}

/// What a surface is, for choosing its pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceClass {
    Floor,
    Wall,
    Ceiling,
    Furniture,
}

/// What told egogen an object's class.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClassedBy {
    /// A word in its name (`floor`, `wall`, `sofa` …).
    Name,
    /// A word in the class label the scan gives it.
    Label,
    /// The orientation and height of its surfaces.
    Orientation,
}

/// A procedural material, built from Cycles' shader nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Pattern {
    WoodPlanks,
    Tiles,
    Carpet,
    Stone,
    Plaster,
    Paint,
    Wallpaper,
    Brick,
    Wood,
    Fabric,
    Leather,
    Metal,
    Plastic,
}

/// One object's drawn material as Blender builds it (and the annotations record it).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShardMaterial {
    /// The object's name in the scene (as in `object_ids`).
    pub object: String,
    pub class: SurfaceClass,
    pub classed_by: ClassedBy,
    pub pattern: Pattern,
    /// Main colour, linear RGB.
    pub base_rgb: [f64; 3],
    /// Second colour (grain, grout, mortar, print, weave), linear RGB.
    pub accent_rgb: [f64; 3],
    /// The pattern's size (m): plank or row width, tile or brick length, cell or blotch size.
    pub scale_m: f64,
    /// Principled BSDF roughness.
    pub roughness: f64,
}

/// What egogen knows of a scene object when it draws its material.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SurfaceFacts {
    pub name: String,
    /// The class label a scan gives it.
    pub label: Option<String>,
    /// It has an image texture or vertex colours of its own.
    pub textured: bool,
    /// A material of it lets light through: never replaced (the depth would change).
    pub see_through: bool,
    /// Shares of its area facing up (normal within 30° of +z), down, and sideways.
    pub area_up: f64,
    pub area_down: f64,
    pub area_side: f64,
    /// Its lowest and highest points above the walked floor (m).
    pub z_min_m: f64,
    pub z_max_m: f64,
}

/// What an object is, finer than [`SurfaceClass`] where a name says more.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Class(SurfaceClass),
    /// A rug or carpet lying on the floor.
    Carpet,
    /// Upholstered: sofas, beds, curtains.
    Soft,
    /// Chairs and stools.
    Seat,
    /// Tables, shelves, cupboards, doors.
    Case,
    /// Lamps.
    Light,
}

impl Kind {
    fn class(self) -> SurfaceClass {
        match self {
            Kind::Class(c) => c,
            Kind::Carpet => SurfaceClass::Floor,
            _ => SurfaceClass::Furniture,
        }
    }

    /// The patterns it draws from, with weights.
    fn patterns(self) -> &'static [(Pattern, f64)] {
        use Pattern::*;
        match self {
            Kind::Class(SurfaceClass::Floor) => {
                &[(WoodPlanks, 2.0), (Tiles, 1.5), (Carpet, 1.0), (Stone, 1.0)]
            }
            Kind::Class(SurfaceClass::Wall) => {
                &[(Plaster, 1.0), (Paint, 1.0), (Wallpaper, 1.5), (Brick, 0.5)]
            }
            // Light plaster: a painted ceiling's colours would be a wall's.
            Kind::Class(SurfaceClass::Ceiling) => &[(Plaster, 1.0)],
            Kind::Class(SurfaceClass::Furniture) => &[
                (Wood, 2.0),
                (Fabric, 1.0),
                (Leather, 0.5),
                (Metal, 0.5),
                (Plastic, 1.0),
            ],
            Kind::Carpet => &[(Carpet, 1.0)],
            Kind::Soft => &[(Fabric, 3.0), (Leather, 1.0)],
            Kind::Seat => &[(Wood, 2.0), (Fabric, 1.0), (Plastic, 1.0), (Metal, 0.5)],
            Kind::Case => &[(Wood, 3.0), (Plastic, 1.0), (Metal, 0.5)],
            Kind::Light => &[(Metal, 1.0), (Plastic, 1.0)],
        }
    }
}

/// What an object's class ([`ObjectClass`], from a word of its name or label) makes it
/// here: `Some(None)` for things whose own material stays (plants, small objects, windows,
/// screens), `None` where its surfaces decide (appliances).
fn kind_of(class: ObjectClass) -> Option<Option<Kind>> {
    use ObjectClass as C;
    Some(match class {
        C::Plant | C::SmallObject | C::Window | C::Screen | C::Picture => None,
        C::Carpet => Some(Kind::Carpet),
        C::Floor => Some(Kind::Class(SurfaceClass::Floor)),
        C::Wall => Some(Kind::Class(SurfaceClass::Wall)),
        C::Ceiling => Some(Kind::Class(SurfaceClass::Ceiling)),
        C::Sofa | C::Bed | C::Textile => Some(Kind::Soft),
        C::Light => Some(Kind::Light),
        C::Seat => Some(Kind::Seat),
        C::Table | C::Storage | C::Door => Some(Kind::Case),
        C::Appliance => return None,
    })
}

fn kind_by_words(text: &str) -> Option<Option<Kind>> {
    ObjectClass::by_words(text).and_then(kind_of)
}

/// An object's class by its surfaces: mostly facing up and low — a floor; mostly facing down
/// and high — a ceiling; mostly sideways and taller than a person — a wall; else furniture.
fn class_by_orientation(f: &SurfaceFacts) -> SurfaceClass {
    if f.area_up >= 0.6 && f.z_max_m <= 0.3 {
        SurfaceClass::Floor
    } else if f.area_down >= 0.6 && f.z_min_m >= 1.8 {
        SurfaceClass::Ceiling
    } else if f.area_side >= 0.5 && f.z_max_m - f.z_min_m >= 1.8 {
        SurfaceClass::Wall
    } else {
        SurfaceClass::Furniture
    }
}

/// Which object of a kind gets what: the class, what said so, and the kind (`None`: keep).
fn classify(f: &SurfaceFacts) -> (Option<Kind>, ClassedBy) {
    if let Some(kind) = kind_by_words(&f.name) {
        return (kind, ClassedBy::Name);
    }
    if let Some(kind) = f.label.as_deref().and_then(kind_by_words) {
        return (kind, ClassedBy::Label);
    }
    (
        Some(Kind::Class(class_by_orientation(f))),
        ClassedBy::Orientation,
    )
}

/// A colour drawn from ranges of hue (degrees), saturation and value.
fn colour(rng: &mut ChaCha8Rng, h: (f64, f64), s: (f64, f64), v: (f64, f64)) -> [f64; 3] {
    let (h, s, v) = (
        uniform_in(rng, h.0, h.1),
        uniform_in(rng, s.0, s.1),
        uniform_in(rng, v.0, v.1),
    );
    hsv_linear(h, s, v)
}

fn scaled(rgb: [f64; 3], k: f64) -> [f64; 3] {
    rgb.map(|c| (c * k).min(1.0))
}

/// Colours, scale (m) and roughness of one pattern.
fn draw_look(rng: &mut ChaCha8Rng, pattern: Pattern) -> ([f64; 3], [f64; 3], f64, f64) {
    use Pattern::*;
    const ANY: (f64, f64) = (0.0, 360.0);
    match pattern {
        WoodPlanks | Wood => {
            let base = colour(rng, (18.0, 40.0), (0.35, 0.7), (0.25, 0.7));
            let grain = uniform_in(rng, 0.55, 0.75);
            let (scale, rough) = match pattern {
                WoodPlanks => (uniform_in(rng, 0.10, 0.22), uniform_in(rng, 0.3, 0.6)),
                _ => (uniform_in(rng, 0.02, 0.08), uniform_in(rng, 0.25, 0.55)),
            };
            (base, scaled(base, grain), scale, rough)
        }
        Tiles => {
            let base = colour(rng, ANY, (0.0, 0.25), (0.45, 0.92));
            let grout = colour(rng, (30.0, 50.0), (0.0, 0.1), (0.25, 0.7));
            (
                base,
                grout,
                uniform_in(rng, 0.2, 0.6),
                uniform_in(rng, 0.1, 0.35),
            )
        }
        Carpet => {
            let base = colour(rng, ANY, (0.1, 0.55), (0.15, 0.65));
            (
                base,
                scaled(base, uniform_in(rng, 0.55, 0.8)),
                uniform_in(rng, 0.15, 0.5),
                uniform_in(rng, 0.85, 1.0),
            )
        }
        Stone => {
            let base = colour(rng, (20.0, 50.0), (0.0, 0.2), (0.35, 0.75));
            (
                base,
                scaled(base, uniform_in(rng, 0.5, 0.75)),
                uniform_in(rng, 0.15, 0.5),
                uniform_in(rng, 0.4, 0.8),
            )
        }
        Plaster => {
            let base = colour(rng, (25.0, 60.0), (0.0, 0.12), (0.6, 0.92));
            (
                base,
                scaled(base, uniform_in(rng, 0.8, 0.9)),
                uniform_in(rng, 0.05, 0.3),
                uniform_in(rng, 0.7, 0.95),
            )
        }
        Paint => {
            let base = colour(rng, ANY, (0.05, 0.4), (0.4, 0.88));
            (
                base,
                scaled(base, uniform_in(rng, 0.85, 0.93)),
                uniform_in(rng, 0.2, 0.8),
                uniform_in(rng, 0.5, 0.8),
            )
        }
        Wallpaper => {
            let hue = uniform_in(rng, 0.0, 360.0);
            let base = colour(rng, (hue, hue), (0.05, 0.35), (0.5, 0.88));
            let print = colour(rng, (hue + 60.0, hue + 300.0), (0.2, 0.55), (0.25, 0.7));
            (
                base,
                print,
                uniform_in(rng, 0.05, 0.2),
                uniform_in(rng, 0.5, 0.85),
            )
        }
        Brick => {
            let base = colour(rng, (5.0, 28.0), (0.4, 0.7), (0.25, 0.55));
            let mortar = colour(rng, (30.0, 50.0), (0.0, 0.12), (0.5, 0.8));
            (
                base,
                mortar,
                uniform_in(rng, 0.2, 0.26),
                uniform_in(rng, 0.75, 0.95),
            )
        }
        Fabric => {
            let base = colour(rng, ANY, (0.1, 0.7), (0.12, 0.7));
            (
                base,
                scaled(base, uniform_in(rng, 0.6, 0.8)),
                uniform_in(rng, 0.002, 0.006),
                uniform_in(rng, 0.8, 1.0),
            )
        }
        Leather => {
            let base = colour(rng, (0.0, 40.0), (0.3, 0.75), (0.06, 0.4));
            (
                base,
                scaled(base, uniform_in(rng, 0.6, 0.8)),
                uniform_in(rng, 0.005, 0.02),
                uniform_in(rng, 0.35, 0.6),
            )
        }
        Metal => {
            let base = colour(rng, (20.0, 60.0), (0.0, 0.1), (0.5, 0.9));
            (
                base,
                scaled(base, 0.85),
                uniform_in(rng, 0.3, 1.0),
                uniform_in(rng, 0.15, 0.45),
            )
        }
        Plastic => {
            let base = colour(rng, ANY, (0.0, 0.8), (0.1, 0.9));
            (
                base,
                scaled(base, 0.9),
                uniform_in(rng, 0.3, 1.0),
                uniform_in(rng, 0.3, 0.6),
            )
        }
    }
}

fn pick(rng: &mut ChaCha8Rng, weighted: &[(Pattern, f64)]) -> Pattern {
    weighted[weighted_index(rng, weighted.iter().map(|p| p.1))].0
}

impl MaterialsPlan {
    /// The drawn material of each object the mode replaces, in the order given. Each object
    /// draws from its own stream (the seed and its name), so adding an object to a scene
    /// leaves the others' materials as they were.
    pub(crate) fn draw(&self, objects: &[SurfaceFacts]) -> Vec<ShardMaterial> {
        if self.mode == MaterialsMode::Keep {
            return Vec::new();
        }
        objects
            .iter()
            .filter(|f| !f.see_through && (self.mode == MaterialsMode::All || !f.textured))
            .filter_map(|f| {
                let (kind, classed_by) = classify(f);
                let kind = kind?;
                let mut rng = ChaCha8Rng::seed_from_u64(self.seed ^ name_hash(&f.name));
                let pattern = pick(&mut rng, kind.patterns());
                let (base_rgb, accent_rgb, scale_m, roughness) = draw_look(&mut rng, pattern);
                Some(ShardMaterial {
                    object: f.name.clone(),
                    class: kind.class(),
                    classed_by,
                    pattern,
                    base_rgb,
                    accent_rgb,
                    scale_m,
                    roughness,
                })
            })
            .collect()
    }
}

/// A stable 64-bit hash of a name (FNV-1a), mixed into the seed.
fn name_hash(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn facts(name: &str, textured: bool) -> SurfaceFacts {
        SurfaceFacts {
            name: name.into(),
            label: None,
            textured,
            see_through: false,
            area_up: 0.1,
            area_down: 0.1,
            area_side: 0.8,
            z_min_m: 0.0,
            z_max_m: 0.9,
        }
    }

    #[test]
    fn names_say_what_an_object_is_at_a_word_s_start() {
        let kind = |n: &str| classify(&facts(n, false)).0;
        assert_eq!(kind("floor_living"), Some(Kind::Class(SurfaceClass::Floor)));
        assert_eq!(kind("IKEA_bed_FJELLSE"), Some(Kind::Soft));
        assert_eq!(kind("IKEA_carpet_DRAGOR"), Some(Kind::Carpet));
        assert_eq!(
            kind("HouseWallB_01_001"),
            Some(Kind::Class(SurfaceClass::Wall))
        );
        assert_eq!(kind("IKEAShelf_mesh.001"), Some(Kind::Case));
        assert_eq!(kind("NightStand_01_002"), Some(Kind::Case));
        assert_eq!(kind("Chandelier_01_001"), Some(Kind::Light));
        assert_eq!(kind("IKEA_Plant_1"), None);
        assert_eq!(
            kind("turtlebot3_house::bookshelf"),
            None,
            "a book word first"
        );
        // `ChairA_01_001`: a chair; `armchair` is soft, not a chair.
        assert_eq!(kind("ChairA_01_001"), Some(Kind::Seat));
        assert_eq!(kind("IKEA_armchair_EKTORP"), Some(Kind::Soft));
        // No word: its surfaces decide (mostly sideways, 0.9 m tall: furniture).
        assert_eq!(
            classify(&facts("C6_plein_ext_P", false)),
            (
                Some(Kind::Class(SurfaceClass::Furniture)),
                ClassedBy::Orientation
            )
        );
    }

    #[test]
    fn orientation_classes_floors_walls_and_ceilings() {
        let mut f = facts("x", false);
        f.z_max_m = 2.6;
        assert_eq!(class_by_orientation(&f), SurfaceClass::Wall);
        f.area_up = 0.9;
        f.area_side = 0.1;
        f.z_max_m = 0.02;
        assert_eq!(class_by_orientation(&f), SurfaceClass::Floor);
        f.area_up = 0.0;
        f.area_down = 0.95;
        f.z_min_m = 2.5;
        f.z_max_m = 2.5;
        assert_eq!(class_by_orientation(&f), SurfaceClass::Ceiling);
    }

    #[test]
    fn modes_choose_which_objects_are_drawn_and_seeds_draw_apart() {
        let mut glass = facts("vase", false);
        glass.see_through = true;
        let objects = [
            facts("floor", false),
            facts("table", true),
            facts("Plant", false),
            glass,
        ];
        let plan = |mode, seed| MaterialsPlan { mode, seed }.draw(&objects);
        assert!(plan(MaterialsMode::Keep, 0).is_empty());
        let fill = plan(MaterialsMode::Fill, 0);
        assert_eq!(
            fill.iter().map(|m| m.object.as_str()).collect::<Vec<_>>(),
            ["floor"]
        );
        let all = plan(MaterialsMode::All, 0);
        assert_eq!(
            all.iter().map(|m| m.object.as_str()).collect::<Vec<_>>(),
            ["floor", "table"]
        );
        // The floor's draw does not depend on which other objects are drawn.
        assert_eq!(fill[0], all[0]);
        assert_eq!(plan(MaterialsMode::All, 0), all, "same seed, same draw");
        let other = plan(MaterialsMode::All, 1);
        assert_ne!(other[0].base_rgb, all[0].base_rgb);
        for m in all.iter().chain(&other) {
            assert!(m
                .base_rgb
                .iter()
                .chain(&m.accent_rgb)
                .all(|c| (0.0..=1.0).contains(c)));
            assert!(m.scale_m > 0.0 && (0.0..=1.0).contains(&m.roughness));
        }
    }

    #[test]
    fn every_pattern_draws_colours_in_range() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for kind in [
            Kind::Class(SurfaceClass::Floor),
            Kind::Class(SurfaceClass::Wall),
            Kind::Class(SurfaceClass::Furniture),
        ] {
            for &(p, _) in kind.patterns() {
                for _ in 0..50 {
                    let (a, b, s, r) = draw_look(&mut rng, p);
                    assert!(a.iter().chain(&b).all(|c| (0.0..=1.0).contains(c)), "{p:?}");
                    assert!(s > 0.0 && s < 1.1 && (0.0..=1.0).contains(&r), "{p:?}");
                }
            }
        }
    }
}
