//! The furniture catalogue a dwelling is furnished from: `catalogue.json` (each model's name,
//! category, size, creator, licence) beside one GLB per model (y up, metres, centred on its
//! footprint, standing on y = 0, its front towards +z: towards −y in egogen's z-up world), as
//! `tools/furniture_catalogue.py` makes them from Sweet Home 3D's CC0 library
//! (`assets/furniture/`); and which part each model plays in a home ([`Role`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::DwellingError;

/// One model of the catalogue.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct CatalogueModel {
    pub id: String,
    pub name: String,
    pub category: String,
    pub creator: String,
    /// Width (x), depth (y) and height (z) of its bounding box (m).
    pub size_m: [f64; 3],
    /// Height over the floor it is meant to hang or stand at (m; 0 on the floor).
    pub elevation_m: f64,
    /// Height of its top surface things may be put on, where it is not its top (m): a chair's
    /// seat, a bed's mattress.
    pub drop_on_top_m: Option<f64>,
    /// Its GLB, relative to the catalogue's folder.
    pub file: String,
}

impl CatalogueModel {
    /// Height of the surface small things stand on (m over the model's base).
    pub(crate) fn surface_m(&self) -> f64 {
        match self.drop_on_top_m {
            Some(h) if h > 0.0 && h <= self.size_m[2] => h,
            _ => self.size_m[2],
        }
    }
}

#[derive(Debug, Deserialize)]
struct CatalogueFile {
    library: String,
    licence: String,
    source: String,
    source_sha256: String,
    models: Vec<CatalogueModel>,
}

/// A catalogue read from its folder.
#[derive(Debug, Clone)]
pub struct Catalogue {
    pub dir: PathBuf,
    pub library: String,
    pub licence: String,
    pub source: String,
    pub source_sha256: String,
    /// Its models by id.
    pub models: BTreeMap<String, CatalogueModel>,
}

/// The catalogue egogen ships (`assets/furniture/`, CC0).
pub fn shipped_catalogue_dir() -> PathBuf {
    crate::paths::crate_root().join("assets/furniture")
}

impl Catalogue {
    /// Reads `dir/catalogue.json`; every model a role names must be there with its file.
    pub fn load(dir: &Path) -> Result<Self, DwellingError> {
        let path = dir.join("catalogue.json");
        let text = std::fs::read_to_string(&path).map_err(|e| DwellingError::Catalogue {
            path: path.clone(),
            message: format!("cannot read it ({e}); the shipped catalogue is assets/furniture/ (tools/furniture_catalogue.py makes it)"),
        })?;
        let file: CatalogueFile =
            serde_json::from_str(&text).map_err(|e| DwellingError::Catalogue {
                path: path.clone(),
                message: format!("not a furniture catalogue: {e}"),
            })?;
        let mut models = BTreeMap::new();
        for m in file.models {
            if !(m.size_m.iter().all(|s| s.is_finite() && *s > 0.0)) {
                return Err(DwellingError::Catalogue {
                    path,
                    message: format!(
                        "model `{}`: size_m must be three positive numbers, got {:?}",
                        m.id, m.size_m
                    ),
                });
            }
            models.insert(m.id.clone(), m);
        }
        if models.is_empty() {
            return Err(DwellingError::Catalogue {
                path,
                message: "it lists no models".into(),
            });
        }
        let catalogue = Catalogue {
            dir: dir.to_owned(),
            library: file.library,
            licence: file.licence,
            source: file.source,
            source_sha256: file.source_sha256,
            models,
        };
        for role in Role::ALL {
            if catalogue.models_for(role).is_empty() {
                return Err(DwellingError::Catalogue {
                    path: path.clone(),
                    message: format!(
                        "no model for the role {role:?} (one of {:?})",
                        role.model_ids()
                    ),
                });
            }
        }
        for m in catalogue.models.values() {
            let file = catalogue.model_path(m);
            if !file.is_file() {
                return Err(DwellingError::Catalogue {
                    path: path.clone(),
                    message: format!("model `{}`: its file {} is missing", m.id, file.display()),
                });
            }
        }
        Ok(catalogue)
    }

    pub(crate) fn model_path(&self, m: &CatalogueModel) -> PathBuf {
        self.dir.join(&m.file)
    }

    /// The catalogue's models that can play `role`, in the role table's order.
    pub(crate) fn models_for(&self, role: Role) -> Vec<&CatalogueModel> {
        role.model_ids()
            .iter()
            .filter_map(|id| self.models.get(*id))
            .collect()
    }
}

/// The part a model plays in a home, which decides where it goes (`furnish`) and the word its
/// object is named by (so that [`crate::scene::ObjectClass`] reads it like any scene's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Role {
    Sofa,
    Armchair,
    DiningTable,
    DiningChair,
    Desk,
    DeskChair,
    Stool,
    Bed,
    Nightstand,
    Wardrobe,
    Bookcase,
    TvCabinet,
    KitchenUnit,
    SinkUnit,
    Cooktop,
    Fridge,
    TallUnit,
    WallUnit,
    Toilet,
    Washbasin,
    Shower,
    TowelRack,
    Plant,
    FloorThing,
    Radiator,
    /// Things put on tables, counters and shelves.
    TableThing,
    KitchenThing,
    BathroomThing,
    /// Things lying on a bedroom's floor or furniture.
    BedroomThing,
}

impl Role {
    pub(crate) const ALL: [Role; 29] = [
        Role::Sofa,
        Role::Armchair,
        Role::DiningTable,
        Role::DiningChair,
        Role::Desk,
        Role::DeskChair,
        Role::Stool,
        Role::Bed,
        Role::Nightstand,
        Role::Wardrobe,
        Role::Bookcase,
        Role::TvCabinet,
        Role::KitchenUnit,
        Role::SinkUnit,
        Role::Cooktop,
        Role::Fridge,
        Role::TallUnit,
        Role::WallUnit,
        Role::Toilet,
        Role::Washbasin,
        Role::Shower,
        Role::TowelRack,
        Role::Plant,
        Role::FloorThing,
        Role::Radiator,
        Role::TableThing,
        Role::KitchenThing,
        Role::BathroomThing,
        Role::BedroomThing,
    ];

    /// The catalogue models (ids of the shipped CC0 library) that play it.
    pub(crate) fn model_ids(self) -> &'static [&'static str] {
        match self {
            Role::Sofa => &["couch", "couch2", "sofa2", "winchester_sofa"],
            Role::Armchair => &[
                "armchair2",
                "modern_armchair",
                "winchester_armchair",
                "armchair",
            ],
            Role::DiningTable => &["oak_table", "table_with_tablecloth", "table"],
            Role::DiningChair => &[
                "oak_chair",
                "plastic_chair",
                "chair",
                "antique_chair",
                "chair_with_cushion",
                "chair2",
                "osaka_chair",
                "thonet",
                "silla_blanca",
            ],
            Role::Desk => &["lb_desk", "desk"],
            Role::DeskChair => &[
                "chair2",
                "thonet",
                "plastic_chair",
                "design_chair",
                "silla_blanca",
            ],
            Role::Stool => &["stool2", "silla2"],
            Role::Bed => &["bed1", "bed2", "bed_with_texture", "bed3"],
            Role::Nightstand => &["bedside_table2"],
            Role::Wardrobe => &["wardrobe_with_sliding_doors", "cupboard"],
            Role::Bookcase => &["bookcase", "vertical_shelves", "shelves"],
            Role::TvCabinet => &["television_cabinet"],
            Role::KitchenUnit => &["lower_cabinet", "drawers_cabinet"],
            Role::SinkUnit => &["sink_cabinet"],
            Role::Cooktop => &["mano_cooktop"],
            Role::Fridge => &["refrigerator", "large_fridge"],
            Role::TallUnit => &["high_cabinet", "double_oven"],
            Role::WallUnit => &["upper_cabinet", "glass_door_cabinet"],
            Role::Toilet => &["toilets_unit"],
            Role::Washbasin => &["washbasin", "modern_vanity"],
            Role::Shower => &["shower_stall"],
            Role::TowelRack => &["towel3"],
            Role::Plant => &[
                "plant",
                "decorative_plant",
                "augalas",
                "orchids",
                "little_plant",
                "cactus",
            ],
            Role::FloorThing => &["umbrella_folded", "electric_guitar", "speaker3"],
            Role::Radiator => &["radiator", "radiator3"],
            Role::TableThing => &[
                "caffe_final",
                "plastic_cup",
                "beer_glass",
                "tetrapak",
                "bread",
                "iphone",
                "headphones",
                "kalender",
                "yogurt_bottle",
                "card_game",
            ],
            Role::KitchenThing => &[
                "kitchenaid",
                "coffee_brewer",
                "knife_stand_swap",
                "bread",
                "tetrapak",
                "caffe_final",
            ],
            Role::BathroomThing => &["cosmetics_pot", "flacon", "comb"],
            Role::BedroomThing => &[
                "slippers",
                "teddy_bear",
                "handbag",
                "bootie",
                "briefcase",
                "basketball",
            ],
        }
    }

    /// The word the object is named by: one [`crate::scene::ObjectClass`] reads.
    pub(crate) fn word(self) -> &'static str {
        match self {
            Role::Sofa => "sofa",
            Role::Armchair => "armchair",
            Role::DiningTable => "table",
            Role::DiningChair | Role::DeskChair => "chair",
            Role::Desk => "desk",
            Role::Stool => "stool",
            Role::Bed => "bed",
            Role::Nightstand => "nightstand",
            Role::Wardrobe => "wardrobe",
            Role::Bookcase => "shelf",
            Role::TvCabinet => "tv",
            Role::KitchenUnit | Role::TallUnit | Role::WallUnit => "cabinet",
            Role::SinkUnit => "sink",
            Role::Cooktop => "stove",
            Role::Fridge => "fridge",
            Role::Toilet => "toilet",
            Role::Washbasin => "washbasin",
            Role::Shower => "shower",
            Role::TowelRack => "rack",
            Role::Plant => "plant",
            Role::FloorThing => "thing",
            Role::Radiator => "radiator",
            Role::TableThing | Role::KitchenThing | Role::BathroomThing | Role::BedroomThing => {
                "thing"
            }
        }
    }
}
