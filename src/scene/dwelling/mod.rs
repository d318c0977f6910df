//! Furnished dwellings generated from a seed and a furniture catalogue (`egogen scene
//! generate`, docs/SCENES.md "Generated dwellings"): a floor plan (`plan`: rooms, walls,
//! doorways, windows), furnished room by room from the catalogue (`catalogue`: Sweet Home 3D's
//! CC0 library as egogen ships it; `furnish`: the placing rules), checked (every room reached
//! over the walkable map from the living room, a seat in the living room, no two pieces'
//! boxes overlapping) and written as one GLB (one named node per object; walls, floors,
//! ceilings, door frames and leaves, window frames and ceiling lamps built by `architecture`,
//! pictures with their paintings hung on the walls by `pictures`, the furniture's meshes and
//! textures copied from the catalogue's GLBs: `glb`) with a JSON
//! sidecar (each object's class, room, catalogue model, creator and licence; the rooms).
//! The same seed, settings and catalogue give the same bytes. `batch` is `egogen scene
//! generate`'s job: dwellings from consecutive seeds, written and summarised; `source` is
//! `dwelling:SEED` wherever a scene file is asked for, and the held-out seeds; `attribution` is
//! what a dwelling placing models of an opt-in (CC-BY) library carries.

mod architecture;
pub(crate) mod attribution;
pub(crate) mod batch;
pub(crate) mod catalogue;
pub(crate) mod furnish;
mod glb;
mod pictures;
pub(crate) mod plan;
mod source;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde::{Deserialize, Serialize};

pub use catalogue::{shipped_catalogue_dir, Catalogue, CatalogueModel, Role};
pub use furnish::Placed;
pub use plan::{FloorPlan, RoomKind};
pub(crate) use source::{dwelling_seed, scene_source, DWELLING_SOURCE, HELD_OUT_SEEDS_FROM};

use crate::math::Vec3;
use crate::scene::{ObjectClass, SceneMesh, SeatSettings, WalkableMap, WalkableSettings};
use architecture::Built;

/// Version of the generator: a dwelling made again with the same seed, settings and version
/// is the same file. 2: the seat finder that checks a living room has a seat finds chairs
/// pulled up to tables and no longer faces a chair sideways (other draws pass; the sidecar's
/// seat counts differ). 3: pictures hang on the walls (`pictures`; the plan and the furniture
/// drawn as in 2, other draws pass where a picture narrows the walkable map); things a hand
/// can pick up on the floors by default (`floor_things` [1, 2], [0, 0] before).
pub(crate) const DWELLING_VERSION: u32 = 3;

/// Plans and furnishings drawn before a seed is given up.
const MAX_TRIES: usize = 40;

/// Largest floor area of one room a settings file may ask for (m²): a hall of 22 m by 22 m.
pub(crate) const MAX_ROOM_M2: f64 = 500.0;

/// How dwellings are drawn (the keys of a settings file, at its top level; every key optional).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DwellingSettings {
    /// Range of the number of bedrooms.
    pub bedrooms: (usize, usize),
    /// Ranges of each room's floor area (m², wall centre to wall centre).
    pub living_m2: (f64, f64),
    pub kitchen_m2: (f64, f64),
    pub bedroom_m2: (f64, f64),
    pub bathroom_m2: (f64, f64),
    pub hall_m2: (f64, f64),
    /// Range of the outline's long side over its short side.
    pub aspect: (f64, f64),
    /// Least side of any room (m).
    pub min_room_side_m: f64,
    /// Range of the ceiling's height (m).
    pub ceiling_m: (f64, f64),
    /// Thickness of inner and outer walls (m).
    pub wall_m: f64,
    pub outer_wall_m: f64,
    /// Range of doorway widths (m).
    pub door_m: (f64, f64),
    /// Share of doorways with a leaf standing open (the rest are open doorways).
    pub door_leaf_share: f64,
    /// Range of window widths (m), of sill heights (m), and the windows' top (m).
    pub window_m: (f64, f64),
    pub window_sill_m: (f64, f64),
    pub window_top_m: f64,
    /// Range of the number of small things put on each table, counter, nightstand or basin.
    pub small_things: (usize, usize),
    /// Range of the number of things a hand can pick up left on the floor of each living
    /// room and bedroom (`furnish::Furnishing::drop_things`).
    pub floor_things: (usize, usize),
}

impl Default for DwellingSettings {
    fn default() -> Self {
        Self {
            bedrooms: (1, 3),
            living_m2: (18.0, 32.0),
            kitchen_m2: (8.0, 14.0),
            bedroom_m2: (9.0, 16.0),
            bathroom_m2: (4.0, 7.0),
            hall_m2: (3.5, 7.0),
            aspect: (1.0, 1.8),
            min_room_side_m: 1.8,
            ceiling_m: (2.5, 2.8),
            wall_m: 0.12,
            outer_wall_m: 0.25,
            door_m: (0.8, 0.95),
            door_leaf_share: 0.6,
            window_m: (0.8, 1.8),
            window_sill_m: (0.9, 1.0),
            window_top_m: 2.2,
            small_things: (0, 3),
            floor_things: (1, 2),
        }
    }
}

impl DwellingSettings {
    /// The first key that cannot make a dwelling, with what was expected.
    pub(crate) fn problem(&self) -> Option<(&'static str, String)> {
        let range = |key: &'static str, (lo, hi): (f64, f64), least: f64, most: f64| {
            (!(lo.is_finite() && hi.is_finite() && least <= lo && lo <= hi && hi <= most)).then(
                || {
                    (
                        key,
                        format!(
                            "expected [min, max] with {least} ≤ min ≤ max ≤ {most}, got [{lo}, {hi}]"
                        ),
                    )
                },
            )
        };
        let side = self.min_room_side_m;
        let fits = |key: &'static str, (_, hi): (f64, f64)| {
            (hi < side * side).then(|| {
                (key, format!("its largest room ({hi} m²) cannot have both sides of min_room_side_m = {side} m"))
            })
        };
        let (b0, b1) = self.bedrooms;
        if b0 > b1 || b1 > 8 {
            return Some((
                "bedrooms",
                format!("expected [min, max] with min ≤ max ≤ 8, got [{b0}, {b1}]"),
            ));
        }
        for (key, (t0, t1)) in [
            ("small_things", self.small_things),
            ("floor_things", self.floor_things),
        ] {
            if t0 > t1 || t1 > 10 {
                return Some((
                    key,
                    format!("expected [min, max] with min ≤ max ≤ 10, got [{t0}, {t1}]"),
                ));
            }
        }
        if !(self.min_room_side_m.is_finite() && (1.2..=10.0).contains(&self.min_room_side_m)) {
            return Some((
                "min_room_side_m",
                format!("expected 1.2–10 m, got {}", self.min_room_side_m),
            ));
        }
        if !(self.wall_m.is_finite() && (0.05..=0.5).contains(&self.wall_m)) {
            return Some((
                "wall_m",
                format!("expected 0.05–0.5 m, got {}", self.wall_m),
            ));
        }
        if !(self.outer_wall_m.is_finite() && (0.05..=0.8).contains(&self.outer_wall_m)) {
            return Some((
                "outer_wall_m",
                format!("expected 0.05–0.8 m, got {}", self.outer_wall_m),
            ));
        }
        if !(0.0..=1.0).contains(&self.door_leaf_share) {
            return Some((
                "door_leaf_share",
                format!("expected 0–1, got {}", self.door_leaf_share),
            ));
        }
        let room = MAX_ROOM_M2;
        range("living_m2", self.living_m2, 1.0, room)
            .or_else(|| range("kitchen_m2", self.kitchen_m2, 1.0, room))
            .or_else(|| range("bedroom_m2", self.bedroom_m2, 1.0, room))
            .or_else(|| range("bathroom_m2", self.bathroom_m2, 1.0, room))
            .or_else(|| range("hall_m2", self.hall_m2, 1.0, room))
            .or_else(|| range("aspect", self.aspect, 1.0, 10.0))
            .or_else(|| range("ceiling_m", self.ceiling_m, 2.2, 10.0))
            .or_else(|| range("door_m", self.door_m, 0.6, 10.0))
            .or_else(|| range("window_m", self.window_m, 0.5, 10.0))
            .or_else(|| range("window_sill_m", self.window_sill_m, 0.0, 10.0))
            .or_else(|| {
                (self.door_m.1 > side - 0.4).then(|| {
                    ("door_m", format!("a doorway {} m wide does not fit a wall of min_room_side_m = {side} m less 0.2 m at each end", self.door_m.1))
                })
            })
            .or_else(|| {
                (!(self.window_top_m.is_finite()
                    && self.window_top_m > self.window_sill_m.1 + 0.3
                    && self.window_top_m < self.ceiling_m.0 - 0.1))
                    .then(|| ("window_top_m", format!("expected above window_sill_m's top by 0.3 m and under ceiling_m's least by 0.1 m, got {}", self.window_top_m)))
            })
            .or_else(|| fits("living_m2", self.living_m2))
            .or_else(|| fits("kitchen_m2", self.kitchen_m2))
            .or_else(|| fits("bedroom_m2", self.bedroom_m2))
            .or_else(|| fits("bathroom_m2", self.bathroom_m2))
            .or_else(|| fits("hall_m2", self.hall_m2))
    }
}

/// Why no dwelling was made.
#[derive(Debug, thiserror::Error)]
pub enum DwellingError {
    #[error("dwelling settings: `{key}`: {message}")]
    Settings { key: &'static str, message: String },
    #[error("furniture catalogue {path}: {message}")]
    Catalogue { path: PathBuf, message: String },
    #[error("{path}: {message}")]
    Model { path: PathBuf, message: String },
    #[error("no valid dwelling from seed {seed} in {tries} tries (the last: {reason}); widen the room areas (`living_m2` …) or lower `min_room_side_m`")]
    NoDwelling {
        seed: u64,
        tries: usize,
        reason: String,
    },
    #[error("writing {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// One generated dwelling: its plan, what stands in it, and the scene mesh egogen walks.
pub struct Dwelling {
    pub seed: u64,
    pub settings: DwellingSettings,
    pub plan: FloorPlan,
    pub placed: Vec<Placed>,
    /// Its objects as the GLB holds them (the same names, ids and triangles).
    pub mesh: SceneMesh,
    /// What each object is, by object id − 1 (its node names in order).
    pub objects: Vec<ObjectRecord>,
    /// Places to sit found in it, per room.
    pub seats_per_room: Vec<usize>,
    /// Plans and furnishings drawn before this one passed the checks.
    pub tries: usize,
    /// Why each earlier draw was drawn again.
    pub redrawn: Vec<String>,
    /// The architecture the plan was built into (what the GLB writes beside the pieces).
    built: Vec<Built>,
}

/// One object of a dwelling, as the sidecar lists it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObjectRecord {
    pub node: String,
    /// The placed piece it is (an index into [`Dwelling::placed`]); none for what the
    /// generator built.
    #[serde(skip)]
    pub piece: Option<usize>,
    pub class: Option<ObjectClass>,
    pub room: Option<String>,
    /// Its catalogue model, name, category and creator; none for what the generator built.
    pub model: Option<String>,
    pub model_name: Option<String>,
    pub category: Option<String>,
    pub creator: Option<String>,
    pub licence: String,
    /// The added (opt-in) library its model comes from; none for the catalogue's own.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub library: Option<String>,
    /// Places to sit `scene::seats` finds on it.
    pub seats: usize,
    pub bbox_min: [f64; 3],
    pub bbox_max: [f64; 3],
}

/// Draws U(lo, hi) from the dwelling's generator.
pub(crate) fn draw(rng: &mut ChaCha8Rng, (lo, hi): (f64, f64)) -> f64 {
    crate::math::random::uniform_in(rng, lo, hi)
}

/// Generates the dwelling of `seed`.
pub fn generate(
    settings: &DwellingSettings,
    catalogue: &Catalogue,
    seed: u64,
) -> Result<Dwelling, DwellingError> {
    if let Some((key, message)) = settings.problem() {
        return Err(DwellingError::Settings { key, message });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut models: BTreeMap<String, SceneMesh> = BTreeMap::new();
    let mut redrawn = Vec::new();
    for tries in 1..=MAX_TRIES {
        let Some(plan) = plan::draw_plan(settings, &mut rng) else {
            redrawn.push("no floor plan fitted the rules".to_string());
            continue;
        };
        let mut furnishing =
            furnish::Furnishing::furnish(&plan, catalogue, settings.small_things, &mut rng);
        furnishing.drop_things(catalogue, settings.floor_things, &mut rng);
        let placed = furnishing.placed;
        let mut built = architecture::build(&plan);
        built.extend(architecture::hang_pictures(
            &plan,
            &placed,
            seed,
            tries as u64,
        ));
        let (mesh, mut objects) = scene_mesh(&plan, &built, &placed, catalogue, &mut models)?;
        match check(&plan, &mesh) {
            Ok((seats_per_room, seats_per_object)) => {
                for (o, n) in objects.iter_mut().zip(seats_per_object) {
                    o.seats = n;
                }
                return Ok(Dwelling {
                    seed,
                    settings: settings.clone(),
                    plan,
                    placed,
                    mesh,
                    objects,
                    seats_per_room,
                    tries,
                    redrawn,
                    built,
                });
            }
            Err(why) => redrawn.push(why),
        }
    }
    Err(DwellingError::NoDwelling {
        seed,
        tries: MAX_TRIES,
        reason: redrawn.pop().unwrap_or_default(),
    })
}

/// The walkable map a dwelling is checked on (egogen's default map).
pub fn dwelling_map(mesh: &SceneMesh) -> Result<WalkableMap, String> {
    WalkableMap::build(mesh, WalkableSettings::default()).map_err(|e| format!("{e:?}"))
}

/// Every room reached from the living room over the walkable map, a seat in the living room;
/// the places to sit per room and per object.
fn check(plan: &FloorPlan, mesh: &SceneMesh) -> Result<(Vec<usize>, Vec<usize>), String> {
    let map = dwelling_map(mesh)?;
    let living = plan
        .rooms
        .iter()
        .position(|r| r.kind == RoomKind::Living)
        .expect("a plan has a living room");
    let components_in = |room: usize| {
        let (lo, hi) = plan.interior(room);
        let mut found = BTreeMap::<u32, usize>::new();
        for j in 0..map.ny {
            for i in 0..map.nx {
                let c = map.centre(i, j);
                let k = j * map.nx + i;
                if c.cmpgt(lo).all() && c.cmplt(hi).all() && map.component[k] > 0 {
                    *found.entry(map.component[k]).or_default() += 1;
                }
            }
        }
        found
    };
    let main = components_in(living)
        .into_iter()
        .max_by_key(|&(c, n)| (n, std::cmp::Reverse(c)))
        .map(|(c, _)| c)
        .ok_or("the living room has no walkable floor")?;
    for room in 0..plan.rooms.len() {
        if components_in(room).get(&main).copied().unwrap_or(0) < 4 {
            return Err(format!(
                "{} is not reached from the living room",
                plan.rooms[room].name
            ));
        }
    }
    let seats = crate::scene::find_seats(mesh, &map, &SeatSettings::default());
    let mut per_room = vec![0; plan.rooms.len()];
    let mut per_object = vec![0; mesh.objects.len()];
    for s in &seats {
        if let Some(r) = plan.room_at(s.pelvis()) {
            per_room[r] += 1;
        }
        per_object[s.object.0 as usize - 1] += 1;
    }
    if per_room[living] == 0 {
        return Err("no seat found in the living room".into());
    }
    Ok((per_room, per_object))
}

/// The name a placed piece's object gets: its role's word and its number.
fn piece_name(p: &Placed, k: usize) -> String {
    format!("{}_{}", p.role.word(), k + 1)
}

/// The dwelling as a scene mesh (the objects in the GLB's order) and its objects' records.
fn scene_mesh(
    plan: &FloorPlan,
    built: &[Built],
    placed: &[Placed],
    catalogue: &Catalogue,
    models: &mut BTreeMap<String, SceneMesh>,
) -> Result<(SceneMesh, Vec<ObjectRecord>), DwellingError> {
    let mut mesh = SceneMesh::default();
    let mut records = Vec::new();
    let mut parts: Vec<(Vec<Vec3>, Vec<[u32; 3]>, bool, bool)> = Vec::new();
    let room_name = |r: Option<usize>| r.map(|r| plan.rooms[r].name.clone());
    for b in built {
        let (mut vertices, mut triangles) = (Vec::new(), Vec::new());
        for (lo, hi) in &b.blocks {
            let base = vertices.len() as u32;
            let (corners, tris) = crate::scene::mesh::box_triangles(*lo, *hi);
            vertices.extend(corners);
            triangles.extend(tris.map(|t| t.map(|i| i + base)));
        }
        let (lo, hi) = bounds(&vertices);
        parts.push((vertices, triangles, b.painting.is_some(), false));
        records.push(ObjectRecord {
            node: b.name.clone(),
            piece: None,
            class: ObjectClass::by_words(&b.name),
            room: room_name(b.room),
            model: None,
            model_name: None,
            category: None,
            creator: None,
            licence: "CC0-1.0".into(),
            library: None,
            seats: 0,
            bbox_min: lo,
            bbox_max: hi,
        });
    }
    for (k, p) in placed.iter().enumerate() {
        let model = &catalogue.models[&p.model];
        if !models.contains_key(&p.model) {
            let path = catalogue.model_path(model);
            let m = crate::scene::load_scene(&path, crate::scene::SceneFrame::default()).map_err(
                |e| DwellingError::Model {
                    path: path.clone(),
                    message: e.to_string(),
                },
            )?;
            models.insert(p.model.clone(), m);
        }
        let m = &models[&p.model];
        let (s, c) = p.yaw().sin_cos();
        let at = DVec2::from_array(p.centre).extend(p.z_m);
        let vertices: Vec<Vec3> = m
            .vertices
            .iter()
            .map(|v| Vec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z) + at)
            .collect();
        let name = piece_name(p, k);
        let (lo, hi) = bounds(&vertices);
        parts.push((
            vertices,
            m.triangles.clone(),
            m.objects.iter().any(|o| o.textured),
            m.objects.iter().any(|o| o.see_through),
        ));
        records.push(ObjectRecord {
            node: name.clone(),
            piece: Some(k),
            class: ObjectClass::by_words(&name),
            room: room_name(Some(p.room)),
            model: Some(model.id.clone()),
            model_name: Some(model.name.clone()),
            category: Some(model.category.clone()),
            creator: Some(model.creator.clone()),
            licence: catalogue.library_of(model).licence.clone(),
            library: (model.library > 0).then(|| catalogue.library_of(model).name.clone()),
            seats: 0,
            bbox_min: lo,
            bbox_max: hi,
        });
    }
    // In name order, as a glTF's objects are read (`scene::load`): object k + 1 is the
    // segmentation id of the GLB's node k in that order.
    let mut order: Vec<usize> = (0..records.len()).collect();
    order.sort_by(|&a, &b| records[a].node.cmp(&records[b].node));
    let mut sorted = Vec::with_capacity(records.len());
    for k in order {
        let (vertices, triangles, textured, see_through) = std::mem::take(&mut parts[k]);
        let id = mesh.add_object(records[k].node.clone(), &vertices, &triangles);
        let object = &mut mesh.objects[id.0 as usize - 1];
        object.textured = textured;
        object.see_through = see_through;
        sorted.push(records[k].clone());
    }
    Ok((mesh, sorted))
}

fn bounds(vertices: &[Vec3]) -> ([f64; 3], [f64; 3]) {
    let lo = vertices
        .iter()
        .fold(Vec3::splat(f64::INFINITY), |a, &v| a.min(v));
    let hi = vertices
        .iter()
        .fold(Vec3::splat(f64::NEG_INFINITY), |a, &v| a.max(v));
    let r = |v: Vec3| v.to_array().map(|x| (x * 1e4).round() / 1e4);
    (r(lo), r(hi))
}

/// The sidecar: how it was made, the catalogue, the rooms, doors, windows and objects.
#[derive(Serialize)]
struct Sidecar<'a> {
    generator: Generator<'a>,
    catalogue: CatalogueRecord<'a>,
    plan: &'a FloorPlan,
    seats_per_room: BTreeMap<&'a str, usize>,
    objects: &'a [ObjectRecord],
}

#[derive(Serialize)]
struct Generator<'a> {
    tool: &'static str,
    version: u32,
    seed: u64,
    settings: &'a DwellingSettings,
}

#[derive(Serialize)]
struct CatalogueRecord<'a> {
    #[serde(flatten)]
    own: &'a catalogue::Library,
    /// Opt-in libraries added to it (what an attribution names).
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    added: &'a [catalogue::Library],
}

/// The files a dwelling is written to in `dir`.
pub fn dwelling_files(dir: &Path) -> (PathBuf, PathBuf) {
    (dir.join("dwelling.glb"), dir.join("dwelling.json"))
}

impl Dwelling {
    /// Writes `dwelling.glb` and `dwelling.json` into `dir` (each whole or not at all).
    pub fn write(&self, catalogue: &Catalogue, dir: &Path) -> Result<(), DwellingError> {
        self.write_glb(catalogue, &dwelling_files(dir).0)
    }

    /// Writes the GLB to `glb_path` and its sidecar beside it (`.json`), the sidecar first:
    /// where the GLB is, both are whole.
    pub(crate) fn write_glb(
        &self,
        catalogue: &Catalogue,
        glb_path: &Path,
    ) -> Result<(), DwellingError> {
        let json_path = glb_path.with_extension("json");
        let io = |path: &Path| {
            let path = path.to_owned();
            move |source| DwellingError::Write { path, source }
        };
        if let Some(dir) = glb_path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io(dir))?;
        }
        let bytes = glb::write(self, catalogue)?;
        let sidecar = Sidecar {
            generator: Generator {
                tool: "egogen scene generate",
                version: DWELLING_VERSION,
                seed: self.seed,
                settings: &self.settings,
            },
            catalogue: CatalogueRecord {
                own: catalogue.own(),
                added: catalogue.added(),
            },
            plan: &self.plan,
            seats_per_room: self
                .plan
                .rooms
                .iter()
                .zip(&self.seats_per_room)
                .map(|(r, &n)| (r.name.as_str(), n))
                .collect(),
            objects: &self.objects,
        };
        let mut json = serde_json::to_string_pretty(&sidecar).expect("the sidecar serialises");
        json.push('\n');
        crate::atomic_file::write_atomically(&json_path, json.as_bytes())
            .map_err(io(&json_path))?;
        if let Some(text) = attribution::of_sidecars(&[json.as_bytes()]).map_err(|message| {
            DwellingError::Model {
                path: json_path.clone(),
                message,
            }
        })? {
            let path = attribution::file_beside(glb_path);
            crate::atomic_file::write_atomically(&path, text.as_bytes()).map_err(io(&path))?;
        }
        crate::atomic_file::write_atomically(glb_path, &bytes).map_err(io(glb_path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_settings_name_their_key() {
        let cases: Vec<(fn(&mut DwellingSettings), &str)> = vec![
            (|s| s.living_m2 = (30.0, 20.0), "living_m2"),
            (|s| s.bathroom_m2 = (-1.0, 5.0), "bathroom_m2"),
            (|s| s.bathroom_m2 = (1.5, 2.0), "bathroom_m2"),
            (|s| s.bedrooms = (3, 1), "bedrooms"),
            (|s| s.door_m = (0.8, 1.9), "door_m"),
            (|s| s.wall_m = f64::NAN, "wall_m"),
            (|s| s.window_top_m = 3.5, "window_top_m"),
            (|s| s.aspect = (1.0, 1e308), "aspect"),
            (|s| s.bedroom_m2 = (9.0, 1e308), "bedroom_m2"),
            (|s| s.living_m2 = (18.0, 501.0), "living_m2"),
            (|s| s.ceiling_m = (2.5, 11.0), "ceiling_m"),
        ];
        for (edit, key) in cases {
            let mut s = DwellingSettings::default();
            edit(&mut s);
            assert_eq!(s.problem().map(|p| p.0), Some(key), "{s:?}");
        }
        assert_eq!(DwellingSettings::default().problem(), None);
    }
}
