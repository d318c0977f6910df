//! Generated dwellings (`egogen scene generate`): the same seed gives the same bytes; the GLB
//! reads back as the scene the generator checked (same objects, names and triangles), every
//! room is reached from the living room over the walkable map, no two pieces' boxes overlap,
//! each living room has a seat; bad settings and a missing catalogue are refused by name with
//! nothing written; an opt-in CC-BY library furnishes dwellings that carry its attribution.

mod common;

use std::process::Command;

use egogen::scene::dwelling::{
    dwelling_files, dwelling_map, generate, shipped_catalogue_dir, Catalogue, DwellingSettings,
    Role, RoomKind,
};
use egogen::scene::{load_scene, SceneFrame};

fn catalogue() -> Catalogue {
    Catalogue::load(&shipped_catalogue_dir()).expect("the shipped catalogue loads")
}

#[test]
fn the_same_seed_writes_the_same_bytes_and_the_glb_reads_back_as_checked() {
    let catalogue = catalogue();
    let settings = DwellingSettings::default();
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let d = generate(&settings, &catalogue, 7).unwrap();
    d.write(&catalogue, &a).unwrap();
    generate(&settings, &catalogue, 7)
        .unwrap()
        .write(&catalogue, &b)
        .unwrap();
    let (glb_a, json_a) = dwelling_files(&a);
    let (glb_b, json_b) = dwelling_files(&b);
    assert_eq!(
        std::fs::read(&glb_a).unwrap(),
        std::fs::read(&glb_b).unwrap()
    );
    assert_eq!(
        std::fs::read(&json_a).unwrap(),
        std::fs::read(&json_b).unwrap()
    );
    let other = generate(&settings, &catalogue, 8).unwrap();
    assert_ne!(other.plan, d.plan, "another seed, another plan");

    let loaded = load_scene(&glb_a, SceneFrame::default()).unwrap();
    let names = |m: &egogen::scene::SceneMesh| -> Vec<String> {
        m.objects.iter().map(|o| o.name.clone()).collect()
    };
    assert_eq!(names(&loaded), names(&d.mesh));
    assert_eq!(loaded.triangles.len(), d.mesh.triangles.len());
    let (lo1, hi1) = loaded.bounds().unwrap();
    let (lo2, hi2) = d.mesh.bounds().unwrap();
    assert!((lo1 - lo2).abs().max_element() < 1e-4 && (hi1 - hi2).abs().max_element() < 1e-4);
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json_a).unwrap()).unwrap();
    let nodes: Vec<&str> = sidecar["objects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o["node"].as_str().unwrap())
        .collect();
    assert_eq!(nodes, names(&loaded));
    assert_eq!(sidecar["generator"]["seed"], 7);
    // Pictures hang with their paintings: textured, so drawn materials leave them as they are.
    let pictures: Vec<_> = loaded
        .objects
        .iter()
        .filter(|o| o.name.starts_with("picture_"))
        .collect();
    assert!(pictures.len() >= 3, "{} pictures", pictures.len());
    assert!(pictures.iter().all(|o| o.textured));
    assert!(sidecar["objects"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|o| o["class"] == "picture")
        .all(|o| o["node"].as_str().unwrap().starts_with("picture_")));
    // Every catalogue piece names its model, creator and licence.
    for o in sidecar["objects"].as_array().unwrap() {
        if o["model"].is_string() {
            assert!(o["creator"].is_string() && o["licence"] == "CC0-1.0", "{o}");
        }
    }
}

#[test]
fn rooms_are_reached_pieces_do_not_overlap_and_living_rooms_have_seats() {
    let catalogue = catalogue();
    let settings = DwellingSettings::default();
    for seed in 100..104 {
        let d = generate(&settings, &catalogue, seed).unwrap();
        let p = &d.placed;
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                let (a, b) = (p[i].rect(), p[j].rect());
                let apart_z = p[i].top_m() <= p[j].z_m + 1e-9 || p[j].top_m() <= p[i].z_m + 1e-9;
                // A thing stands on its support's surface (a basin's, a seat's), inside its box.
                let on = |x: &egogen::scene::dwelling::Placed,
                          y: &egogen::scene::dwelling::Placed| {
                    let (rx, ry) = (x.rect(), y.rect());
                    x.z_m > y.z_m + 1e-9
                        && rx.min.cmpge(ry.min - 1e-9).all()
                        && rx.max.cmple(ry.max + 1e-9).all()
                };
                assert!(
                    !a.overlaps(&b) || apart_z || on(&p[i], &p[j]) || on(&p[j], &p[i]),
                    "seed {seed}: {} and {} overlap",
                    p[i].model,
                    p[j].model
                );
            }
            let (lo, hi) = d.plan.interior(p[i].room);
            let r = p[i].rect();
            assert!(r.min.cmpge(lo - 1e-6).all() && r.max.cmple(hi + 1e-6).all());
        }
        let map = dwelling_map(&d.mesh).unwrap();
        let living = d
            .plan
            .rooms
            .iter()
            .position(|r| r.kind == RoomKind::Living)
            .unwrap();
        assert!(d.seats_per_room[living] >= 1, "seed {seed}");
        // One walkable component holds floor of every room.
        let centre_component = |room: usize| {
            let (lo, hi) = d.plan.interior(room);
            let mut found = std::collections::BTreeSet::new();
            for j in 0..map.ny {
                for i in 0..map.nx {
                    let c = map.centre(i, j);
                    let k = j * map.nx + i;
                    if c.cmpgt(lo).all() && c.cmplt(hi).all() && map.component[k] > 0 {
                        found.insert(map.component[k]);
                    }
                }
            }
            found
        };
        let shared = (0..d.plan.rooms.len())
            .map(centre_component)
            .reduce(|a, b| a.intersection(&b).copied().collect())
            .unwrap();
        assert!(
            !shared.is_empty(),
            "seed {seed}: no component reaches every room"
        );
        assert!(
            d.placed.iter().any(|p| p.role == Role::Bed),
            "seed {seed}: no bed"
        );
    }
}

fn egogen(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(args)
        .output()
        .unwrap()
}

/// `egogen scene generate --seed SEED --out OUT EXTRA…`.
fn scene_generate(seed: &str, out: &std::path::Path, extra: &[&str]) -> std::process::Output {
    let out = out.to_str().unwrap();
    egogen(&[&["scene", "generate", "--seed", seed, "--out", out], extra].concat())
}

/// `egogen scene generate --out OUT FLAG VALUE` fails; its standard error.
fn refused(out: &std::path::Path, flag: &str, value: &std::path::Path) -> String {
    let o = egogen(&[
        "scene",
        "generate",
        "--out",
        out.to_str().unwrap(),
        flag,
        value.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn bad_settings_or_a_missing_catalogue_are_refused_by_name_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let settings = dir.path().join("bad.toml");
    let out = dir.path().join("out");
    std::fs::write(&settings, "bathroom_m2 = [-3.0, 5.0]\n").unwrap();
    let err = refused(&out, "--settings", &settings);
    assert!(
        err.contains("bathroom_m2") && err.contains("bad.toml"),
        "{err}"
    );
    std::fs::write(&settings, "rooms = 3\n").unwrap();
    let err = refused(&out, "--settings", &settings);
    assert!(err.contains("rooms"), "{err}");

    let empty = dir.path().join("empty_catalogue");
    std::fs::create_dir(&empty).unwrap();
    let err = refused(&out, "--catalogue", &empty);
    assert!(err.contains("catalogue.json"), "{err}");
    std::fs::write(
        empty.join("catalogue.json"),
        r#"{"library":"x","licence":"CC0-1.0","source":"x","source_sha256":"0","models":[]}"#,
    )
    .unwrap();
    let err = refused(&out, "--catalogue", &empty);
    assert!(err.contains("no models"), "{err}");
    assert!(!out.exists());

    // A dwelling that is there is not overwritten.
    let o = scene_generate("3", &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let before = std::fs::read(dwelling_files(&out).0).unwrap();
    let o = scene_generate("4", &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("already exists"),
        "{err}"
    );
    assert_eq!(std::fs::read(dwelling_files(&out).0).unwrap(), before);
}

/// A campaign's `dwellings` as a range, `{ first, count }`: its dry run prices generating
/// each (nothing is written); a range or list that cannot be seeds, or a `dwelling_catalogues`
/// folder that holds no catalogue, is refused naming the key.
#[test]
fn a_campaign_names_its_dwellings_by_range_and_bad_ranges_are_refused() {
    let a = tempfile::tempdir().unwrap();
    common::tiny_campaign_run(a.path(), false);
    let out = a.path().join("campaign");
    let campaign = a.path().join("dwellings.toml");
    let dry_run = |dwellings: &str| {
        std::fs::write(
            &campaign,
            format!(
                "[campaign]\nrun = \"run.toml\"\nout = \"{}\"\ntakes = 4\ndwellings = {dwellings}\ncrowd_count = [1, 1]\nmin_free_disk_gb = 0.0\n",
                out.display()
            ),
        )
        .unwrap();
        Command::new(env!("CARGO_BIN_EXE_egogen-run"))
            .arg(&campaign)
            .arg("--dry-run")
            .output()
            .unwrap()
    };
    let o = dry_run("{ first = 40, count = 3 }");
    let said = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{said}");
    assert!(said.contains("3 dwelling(s) to generate first"), "{said}");
    assert!(!out.exists(), "a dry run writes nothing");
    for (dwellings, says) in [
        ("{ first = 40 }", "`count` is missing"),
        ("{ first = 40, count = 0 }", "`count` is 0"),
        ("{ first = -1, count = 2 }", "`first` is -1"),
        ("{ from = 1, count = 2 }", "unknown key `from`"),
        ("[1, -2]", "entry 1 is -2"),
        ("\"1-5\"", "is not a list of seeds"),
    ] {
        let o = dry_run(dwellings);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{dwellings}");
        assert!(
            err.contains("campaign.dwellings") && err.contains(says),
            "{dwellings}: {err}"
        );
    }
    // Generator settings that cannot make a dwelling are refused naming the key and the file's.
    std::fs::write(a.path().join("ft.toml"), "floor_things = [3, 1]\n").unwrap();
    let o = dry_run("[1]\ndwelling_settings = \"ft.toml\"");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("campaign.dwelling_settings") && err.contains("`floor_things`"),
        "{err}"
    );
    // An added furniture library that is not one is refused before anything is planned.
    let o = dry_run("[1]\ndwelling_catalogues = [\"nowhere\"]");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("campaign.dwelling_catalogues")
            && err.contains("nowhere holds no catalogue.json"),
        "{err}"
    );
}

/// A campaign's `dwellings` are generated once into its `scenes/` (the same bytes as `egogen
/// scene generate`), rendered like any scene, and a run config names one as `dwelling:SEED`
/// (generated into the cache, the same file again).
#[test]
fn a_campaign_and_a_run_config_walk_generated_dwellings() {
    let a = tempfile::tempdir().unwrap();
    common::tiny_campaign_run(a.path(), false);
    let out = a.path().join("campaign");
    let campaign = a.path().join("dwellings.toml");
    std::fs::write(
        &campaign,
        format!(
            "[campaign]\nrun = \"run.toml\"\nout = \"{}\"\ntakes = 1\ndwellings = [5]\ncrowd_count = [1, 1]\nmin_free_disk_gb = 0.0\n",
            out.display()
        ),
    )
    .unwrap();
    common::succeeds(Command::new(env!("CARGO_BIN_EXE_egogen-run")).arg(&campaign));
    let state = egogen::campaign::CampaignState::read(&out).unwrap();
    assert!(state.takes[0].def.scene.ends_with("scenes/dwelling_5.glb"));
    assert_eq!(
        state.takes[0].status,
        egogen::campaign::TakeStatus::Complete
    );
    let alone = a.path().join("alone");
    let o = scene_generate("5", &alone, &[]);
    assert!(o.status.success());
    let (glb, json) = dwelling_files(&alone);
    assert_eq!(
        std::fs::read(glb).unwrap(),
        std::fs::read(out.join("scenes/dwelling_5.glb")).unwrap()
    );
    assert_eq!(
        std::fs::read(json).unwrap(),
        std::fs::read(out.join("scenes/dwelling_5.json")).unwrap()
    );

    // With the generator's settings: the dwelling `scene generate --settings` makes, without
    // the things a hand can pick up that the default leaves on its floors.
    std::fs::write(a.path().join("ft.toml"), "floor_things = [0, 0]\n").unwrap();
    let with_things = a.path().join("with_things");
    std::fs::write(
        &campaign,
        format!(
            "[campaign]\nrun = \"run.toml\"\nout = \"{}\"\ntakes = 1\ndwellings = [5]\ndwelling_settings = \"ft.toml\"\ncrowd_count = [1, 1]\nmin_free_disk_gb = 0.0\n",
            with_things.display()
        ),
    )
    .unwrap();
    common::succeeds(Command::new(env!("CARGO_BIN_EXE_egogen-run")).arg(&campaign));
    let settings = a.path().join("ft.toml");
    let o = scene_generate(
        "5",
        &a.path().join("alone_ft"),
        &["--settings", settings.to_str().unwrap()],
    );
    assert!(o.status.success());
    let (glb, json) = dwelling_files(&a.path().join("alone_ft"));
    let made = std::fs::read(with_things.join("scenes/dwelling_5.glb")).unwrap();
    assert_eq!(std::fs::read(glb).unwrap(), made);
    assert_ne!(
        made,
        std::fs::read(out.join("scenes/dwelling_5.glb")).unwrap()
    );
    let sidecar = std::fs::read_to_string(json).unwrap();
    assert!(
        sidecar.contains("\"floor_things\": [\n        0,\n        0\n      ]"),
        "{sidecar}"
    );

    // `dwelling:SEED` in a run config: generated into the cache (EGOGEN_CACHE) on first use.
    let cache = a.path().join("cache");
    let run = a.path().join("motion_only.toml");
    std::fs::write(
        &run,
        format!("[body]\n[motion]\nsource = \"agents\"\nduration_s = 0.5\n[crowd]\ncount = 1\nlayout = \"random\"\n[output]\ndir = \"{}\"\n[scene]\npath = \"dwelling:5\"\n", a.path().join("take").display()),
    )
    .unwrap();
    common::succeeds(
        Command::new(env!("CARGO_BIN_EXE_egogen-run"))
            .arg(&run)
            .env("EGOGEN_CACHE", &cache),
    );
    let cached: Vec<_> = walk(&cache)
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "glb"))
        .collect();
    assert_eq!(cached.len(), 1, "{cached:?}");
    assert_eq!(
        std::fs::read(&cached[0]).unwrap(),
        std::fs::read(out.join("scenes/dwelling_5.glb")).unwrap()
    );
    let bad = std::fs::write(
        &run,
        "[body]\n[motion]\nsource = \"agents\"\n[output]\ndir = \"x\"\n[scene]\npath = \"dwelling:five\"\n",
    );
    bad.unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_egogen-run"))
        .arg(&run)
        .env("EGOGEN_CACHE", &cache)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("scene.path") && err.contains("dwelling:SEED"),
        "{err}"
    );
}

fn walk(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// An opt-in library in `dir`: three shipped GLBs under new ids and the roles they play, under
/// CC-BY-3.0 (`extra` is spliced into its catalogue.json's top level, `first_id` names its
/// first model).
fn opt_in_library(dir: &std::path::Path, first_id: &str, extra: &str) {
    std::fs::create_dir_all(dir).unwrap();
    let shipped = shipped_catalogue_dir();
    let mut models = Vec::new();
    for (id, from, roles) in [
        (
            first_id,
            "plastic_cup",
            r#"["table_thing", "kitchen_thing"]"#,
        ),
        ("lib_bread", "bread", r#"["table_thing"]"#),
        ("lib_chair", "chair", r#"["dining_chair", "desk_chair"]"#),
    ] {
        std::fs::copy(
            shipped.join(format!("{from}.glb")),
            dir.join(format!("{id}.glb")),
        )
        .unwrap();
        let m = &catalogue().models[from];
        models.push(format!(
            r#"{{"id": "{id}", "name": "Lib {}", "category": "{}", "creator": "A. Maker", "size_m": {:?}, "elevation_m": 0.0, "drop_on_top_m": null, "file": "{id}.glb", "roles": {roles}}}"#,
            m.name, m.category, m.size_m
        ));
    }
    std::fs::write(
        dir.join("catalogue.json"),
        format!(
            r#"{{"library": "Lib", "licence": "CC-BY-3.0", "source": "a test", "source_sha256": "00", {extra} "models": [{}]}}"#,
            models.join(", ")
        ),
    )
    .unwrap();
}

const ATTRIBUTED: &str = r#""licence_url": "https://creativecommons.org/licenses/by/3.0/", "copyright": "2026, A. Maker","#;

/// A CC-BY library added to the shipped catalogue (`--with-catalogue`, a campaign's
/// `dwelling_catalogues`) furnishes dwellings beside the CC0 one; each object records its
/// library and licence, and the dwelling, the campaign and every take made in it carry an
/// attribution naming exactly the added library's models placed, with their creators. Without
/// it the same seed is the same CC0 dwelling as ever. A library with an id already taken, with
/// no licence deed or copyright, or with a role egogen does not know is refused by name.
#[test]
fn an_opt_in_cc_by_library_furnishes_dwellings_that_carry_its_attribution() {
    let a = tempfile::tempdir().unwrap();
    let lib = a.path().join("lib");
    opt_in_library(&lib, "lib_cup", ATTRIBUTED);
    let out = a.path().join("with");
    let o = scene_generate("5", &out, &["--with-catalogue", lib.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (glb, json) = dwelling_files(&out);
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(sidecar["catalogue"]["added"][0]["library"], "Lib");
    let objects = sidecar["objects"].as_array().unwrap();
    let from_lib: std::collections::BTreeSet<&str> = objects
        .iter()
        .filter(|o| o["library"] == "Lib")
        .map(|o| {
            assert_eq!(o["licence"], "CC-BY-3.0", "{o}");
            o["model"].as_str().unwrap()
        })
        .collect();
    assert!(
        !from_lib.is_empty(),
        "dwelling 5 places none of the library's models"
    );
    assert!(objects
        .iter()
        .filter(|o| o["library"].is_null() && o["model"].is_string())
        .all(|o| o["licence"] == "CC0-1.0"));
    let attribution = std::fs::read_to_string(glb.with_extension("attribution.md")).unwrap();
    assert!(
        attribution.contains("## Lib: CC-BY-3.0 (https://creativecommons.org/licenses/by/3.0/)")
    );
    assert!(
        attribution.contains("Copyright 2026, A. Maker."),
        "{attribution}"
    );
    for id in ["lib_cup", "lib_bread", "lib_chair"] {
        assert_eq!(
            attribution.contains(&format!("| `{id}` | Lib ")),
            from_lib.contains(id),
            "{id}: {attribution}"
        );
    }
    assert!(attribution.contains("| A. Maker |"));

    // Without the library: seed 5 as ever, nothing to attribute.
    let plain = a.path().join("plain");
    let o = scene_generate("5", &plain, &[]);
    assert!(o.status.success());
    let plain_sidecar = std::fs::read_to_string(dwelling_files(&plain).1).unwrap();
    assert!(
        !plain_sidecar.contains("\"added\"") && !plain_sidecar.contains("\"library\": \"Lib\"")
    );
    assert!(!dwelling_files(&plain)
        .0
        .with_extension("attribution.md")
        .exists());
    assert_ne!(
        std::fs::read(&glb).unwrap(),
        std::fs::read(dwelling_files(&plain).0).unwrap()
    );

    // A campaign furnished with it: the same dwelling, its attribution at the campaign's top
    // and in the take (listed in its manifest).
    common::tiny_campaign_run(a.path(), false);
    let campaign_out = a.path().join("campaign");
    let campaign = a.path().join("dwellings.toml");
    std::fs::write(
        &campaign,
        format!(
            "[campaign]\nrun = \"run.toml\"\nout = \"{}\"\ntakes = 1\ndwellings = [5]\ndwelling_catalogues = [\"lib\"]\ncrowd_count = [1, 1]\nmin_free_disk_gb = 0.0\n",
            campaign_out.display()
        ),
    )
    .unwrap();
    common::succeeds(Command::new(env!("CARGO_BIN_EXE_egogen-run")).arg(&campaign));
    assert_eq!(
        std::fs::read(&glb).unwrap(),
        std::fs::read(campaign_out.join("scenes/dwelling_5.glb")).unwrap()
    );
    assert_eq!(
        std::fs::read_to_string(campaign_out.join("ATTRIBUTION.md")).unwrap(),
        attribution
    );
    let state = egogen::campaign::CampaignState::read(&campaign_out).unwrap();
    let take = campaign_out.join("takes").join(&state.takes[0].def.id);
    assert_eq!(
        std::fs::read_to_string(take.join("ATTRIBUTION.md")).unwrap(),
        attribution
    );
    let manifest = std::fs::read_to_string(take.join("manifest.json")).unwrap();
    assert!(manifest.contains("\"ATTRIBUTION.md\""), "{manifest}");

    // Refused by name, nothing written.
    for (name, first_id, extra, says) in [
        ("taken", "chair", ATTRIBUTED, "model `chair` is already in"),
        ("unattributed", "lib_cup", "", "licence_url"),
        (
            "unknown_role",
            "lib_cup",
            ATTRIBUTED,
            "unknown variant `lamp`",
        ),
    ] {
        let bad = a.path().join(name);
        opt_in_library(&bad, first_id, extra);
        if name == "unknown_role" {
            let path = bad.join("catalogue.json");
            let text = std::fs::read_to_string(&path).unwrap();
            std::fs::write(&path, text.replacen("\"table_thing\", ", "\"lamp\", ", 1)).unwrap();
        }
        let dir = a.path().join(format!("out_{name}"));
        let err = refused(&dir, "--with-catalogue", &bad);
        assert!(
            err.contains(says) && err.contains(&format!("{name}/catalogue.json")),
            "{name}: {err}"
        );
        assert!(!dir.exists(), "{name}");
    }
}
