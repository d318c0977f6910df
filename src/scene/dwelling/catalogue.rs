//! The furniture catalogue a dwelling is furnished from: `catalogue.json` (each model's name,
//! category, size, creator, licence) beside one GLB per model (y up, metres, centred on its
//! footprint, standing on y = 0, its front towards +z: towards −y in egogen's z-up world), as
//! `tools/furniture_catalogue.py` makes them from Sweet Home 3D's CC0 library
//! (`assets/furniture/`); which part each model plays in a home ([`Role`]: a table here for the
//! shipped library); and opt-in libraries added to it ([`Catalogue::with_added`]: CC-BY ones
//! the same tool converts, each model naming its own roles, each library its licence and
//! copyright for the attribution its dwellings carry).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

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
    /// The parts it plays, where its catalogue says (an opt-in library's models; the shipped
    /// library's are [`Role::model_ids`]).
    #[serde(default)]
    pub roles: Vec<Role>,
    /// Which of the catalogue's libraries it comes from: 0 its own, k its k-th added one.
    #[serde(skip)]
    pub(crate) library: usize,
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
    #[serde(flatten)]
    library: Library,
    models: Vec<CatalogueModel>,
}

/// A library of a catalogue (its own, or one added): where it is, what it is and under which
/// terms.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct Library {
    #[serde(skip)]
    pub(crate) dir: PathBuf,
    #[serde(rename = "library")]
    pub(crate) name: String,
    pub(crate) licence: String,
    /// The licence's deed and the library's copyright line (an opt-in library names both).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) licence_url: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) copyright: Option<String>,
    pub(crate) source: String,
    pub(crate) source_sha256: String,
}

/// A catalogue read from its folder.
#[derive(Debug, Clone)]
pub struct Catalogue {
    /// Its libraries: its own first, then the opt-in ones added to it, in the order added.
    pub(crate) libraries: Vec<Library>,
    /// Its models by id (its added libraries' too).
    pub models: BTreeMap<String, CatalogueModel>,
}

/// The catalogue egogen ships (`assets/furniture/`, CC0).
pub fn shipped_catalogue_dir() -> PathBuf {
    crate::paths::crate_root().join("assets/furniture")
}

impl Catalogue {
    /// Reads `dir/catalogue.json`; every model a role names must be there with its file.
    pub fn load(dir: &Path) -> Result<Self, DwellingError> {
        let (library, models) = read_folder(dir, 0)?;
        let path = dir.join("catalogue.json");
        let catalogue = Catalogue {
            libraries: vec![library],
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
        Ok(catalogue)
    }

    /// The catalogue in `dir` with the libraries in `added` added ([`Catalogue::with_added`]).
    pub(crate) fn load_with(dir: &Path, added: &[PathBuf]) -> Result<Self, DwellingError> {
        added
            .iter()
            .try_fold(Self::load(dir)?, |c, a| c.with_added(a))
    }

    /// This catalogue with the library in `dir` added (an opt-in one `tools/furniture_catalogue.py
    /// --library` made): its models play the roles each names, beside this one's. Its ids
    /// must be new, and a library under a licence other than CC0 must name the licence's deed
    /// and its copyright (what the attribution of a dwelling that uses it says).
    pub(crate) fn with_added(mut self, dir: &Path) -> Result<Self, DwellingError> {
        let (library, models) = read_folder(dir, self.libraries.len())?;
        let path = dir.join("catalogue.json");
        let bad = |message: String| DwellingError::Catalogue {
            path: path.clone(),
            message,
        };
        if library.licence != "CC0-1.0"
            && (library.licence_url.is_none() || library.copyright.is_none())
        {
            return Err(bad(format!(
                "library `{}` is under {} but does not name `licence_url` and `copyright`, which its dwellings' attribution needs (make it with tools/furniture_catalogue.py --library)",
                library.name, library.licence
            )));
        }
        for (id, m) in models {
            if let Some(was) = self.models.get(&id) {
                return Err(bad(format!(
                    "model `{id}` is already in {} (an added library's ids must be new)",
                    self.libraries[was.library].dir.display()
                )));
            }
            self.models.insert(id, m);
        }
        self.libraries.push(library);
        Ok(self)
    }

    /// The catalogue's own library.
    pub(crate) fn own(&self) -> &Library {
        &self.libraries[0]
    }

    /// The libraries added to it.
    pub(crate) fn added(&self) -> &[Library] {
        &self.libraries[1..]
    }

    /// The library a model comes from.
    pub(crate) fn library_of(&self, m: &CatalogueModel) -> &Library {
        &self.libraries[m.library]
    }

    pub(crate) fn model_path(&self, m: &CatalogueModel) -> PathBuf {
        self.library_of(m).dir.join(&m.file)
    }

    /// The catalogue's models that can play `role`: the role table's, in its order, then the
    /// added libraries' that name it, by id.
    pub(crate) fn models_for(&self, role: Role) -> Vec<&CatalogueModel> {
        let table = role
            .model_ids()
            .iter()
            .filter_map(|id| self.models.get(*id));
        let named = self
            .models
            .values()
            .filter(|m| m.library > 0 && m.roles.contains(&role));
        table.chain(named).collect()
    }
}

/// Reads one catalogue folder: its library and its models (marked as library `library`), each
/// of a positive size with its file there.
fn read_folder(
    dir: &Path,
    library: usize,
) -> Result<(Library, BTreeMap<String, CatalogueModel>), DwellingError> {
    let path = dir.join("catalogue.json");
    let bad = |message: String| DwellingError::Catalogue {
        path: path.clone(),
        message,
    };
    let text = std::fs::read_to_string(&path).map_err(|e| {
        bad(format!("cannot read it ({e}); the shipped catalogue is assets/furniture/ (tools/furniture_catalogue.py makes it)"))
    })?;
    let file: CatalogueFile =
        serde_json::from_str(&text).map_err(|e| bad(format!("not a furniture catalogue: {e}")))?;
    let mut models = BTreeMap::new();
    for mut m in file.models {
        if !(m.size_m.iter().all(|s| s.is_finite() && *s > 0.0)) {
            return Err(bad(format!(
                "model `{}`: size_m must be three positive numbers, got {:?}",
                m.id, m.size_m
            )));
        }
        let file = dir.join(&m.file);
        if !file.is_file() {
            return Err(bad(format!(
                "model `{}`: its file {} is missing",
                m.id,
                file.display()
            )));
        }
        m.library = library;
        models.insert(m.id.clone(), m);
    }
    if models.is_empty() {
        return Err(bad("it lists no models".into()));
    }
    Ok((
        Library {
            dir: dir.to_owned(),
            ..file.library
        },
        models,
    ))
}

/// The part a model plays in a home, which decides where it goes (`furnish`) and the word its
/// object is named by (so that [`crate::scene::ObjectClass`] reads it like any scene's). An
/// opt-in library's catalogue.json names a model's roles in snake case (`dining_chair`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Deserialize)]
#[serde(rename_all = "snake_case")]
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
