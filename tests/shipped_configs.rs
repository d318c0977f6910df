//! Every policy-training and synth config shipped under `configs/` loads through the loader its
//! command uses, so a misspelt key or a wrong path fails here rather than in a user's first run.
//! The one error allowed is a chained run's `init_weights` under `out/` (written by the config
//! before it in its chain, so absent from a fresh checkout).

mod common;

use std::path::Path;

/// The top-level tables and keys of a config file.
fn top_level(path: &Path) -> toml::Table {
    let text = std::fs::read_to_string(path).unwrap();
    text.parse::<toml::Table>()
        .unwrap_or_else(|e| panic!("{}: not TOML: {e}", path.display()))
}

/// Whether a config's `init_weights` names a file under the repository's `out/` that is not
/// there (the previous run of its chain has not been made here).
fn chained_weights_missing(path: &Path, table: &toml::Table) -> bool {
    let Some(init) = table.get("init_weights").and_then(|v| v.as_str()) else {
        return false;
    };
    let weights = path.parent().unwrap().join(init);
    weights.components().any(|c| c.as_os_str() == "out") && !weights.exists()
}

#[test]
fn every_shipped_policy_and_synth_config_loads() {
    let root = common::repo_root();
    let (mut policies, mut synths) = (0, 0);
    for path in common::files_with_extension(&root.join("configs"), "toml") {
        let table = top_level(&path);
        if table.contains_key("stages") {
            match egogen::cli::train_policy::load_policy_plan(&path) {
                Ok(_) => policies += 1,
                Err(_) if chained_weights_missing(&path, &table) => {}
                Err(e) => panic!("{e}"),
            }
        } else if (table.contains_key("crowd") || table.contains_key("agents"))
            && !table.contains_key("render")
        {
            egogen::cli::synth_config::load_synth_plan(&path).unwrap_or_else(|e| panic!("{e}"));
            synths += 1;
        }
    }
    // The shipped chain's configs and the four synth takes of docs/SYNTH.md at least.
    assert!(policies >= 8, "{policies} policy configs loaded");
    assert!(synths >= 4, "{synths} synth configs loaded");
}

#[test]
fn the_shipped_policy_config_writes_the_shipped_policy() {
    let root = common::repo_root();
    let plan = egogen::cli::train_policy::load_policy_plan(
        &root.join(egogen::policy::weights::SHIPPED_POLICY_CONFIG),
    )
    .unwrap();
    let written = std::fs::canonicalize(&plan.weights_out).unwrap();
    let shipped =
        std::fs::canonicalize(root.join(egogen::policy::weights::SHIPPED_POLICY)).unwrap();
    assert_eq!(written, shipped);
}

/// `configs/campaign_dwellings.toml`: 100 takes, each in a dwelling of its own.
#[test]
fn the_shipped_dwellings_campaign_walks_a_dwelling_per_take() {
    let root = common::repo_root();
    let plan = egogen::campaign::plan_campaign(&root.join("configs/campaign_dwellings.toml"))
        .unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(plan.takes.len(), 100);
    for (k, take) in plan.takes.iter().enumerate() {
        let name = format!("dwelling_{}.glb", 20000 + k);
        assert!(
            take.scene.ends_with(format!("scenes/{name}")),
            "{:?}",
            take.scene
        );
    }
}

#[test]
fn the_shipped_campaign_plans_its_takes() {
    let root = common::repo_root();
    let plan = egogen::campaign::plan_campaign(&root.join("configs/campaign.toml"))
        .unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(plan.takes.len(), 12);
    let scenes: std::collections::BTreeSet<_> = plan.takes.iter().map(|t| &t.scene).collect();
    assert_eq!(scenes.len(), 3, "the apartment and two dwellings");
    assert!(plan.takes.iter().all(|t| {
        let n = t.crowd_count.unwrap();
        let d = t.duration_s.unwrap();
        (2..=4).contains(&n) && (6.0..=10.0).contains(&d)
    }));
    // Ids are stable: planned twice, the same.
    let again = egogen::campaign::plan_campaign(&root.join("configs/campaign.toml")).unwrap();
    assert_eq!(plan.fingerprint, again.fingerprint);
    // Planned as before: no take names a frame, so ids and the fingerprint stay those of
    // campaigns planned before scene entries could give one.
    assert!(plan
        .takes
        .iter()
        .all(|t| t.up_axis.is_none() && t.unit_m.is_none()));

    // Beside a run config that reads its scenes in centimetres, a floor plan (written z up in
    // metres) and the dwellings (glTF: y up in metres) are read in their own frame, said per
    // take and in each take's command; a
    // scene entry gives its own frame; the apartment, a plain path, is read as the run config
    // says.
    let dir = tempfile::tempdir().unwrap();
    let run = std::fs::read_to_string(root.join("configs/default.toml"))
        .unwrap()
        .replace("[scene]\n", "[scene]\nunit_m = 0.01\n")
        .replace("\"../", &format!("\"{}/", root.display()));
    assert!(run.contains("unit_m = 0.01"));
    std::fs::write(dir.path().join("cm.toml"), run).unwrap();
    std::fs::write(dir.path().join("room_cm.obj"), common::room_y_up_cm_obj()).unwrap();
    let write_campaign = |scenes: &str| {
        let campaign = std::fs::read_to_string(root.join("configs/campaign.toml"))
            .unwrap()
            .replace("run = \"default.toml\"", "run = \"cm.toml\"")
            .replace("# floor_plans = [1, 2]", "floor_plans = [3]")
            .replace(
                "scenes = [\"../assets/scenes/apartment.glb\"]",
                &format!("scenes = {scenes}"),
            )
            .replace("\"../", &format!("\"{}/", root.display()));
        assert!(campaign.contains(scenes), "{campaign}");
        let path = dir.path().join("campaign.toml");
        std::fs::write(&path, campaign).unwrap();
        egogen::campaign::plan_campaign(&path).map_err(|e| format!("{e:#}"))
    };
    let apartment = root.join("assets/scenes/apartment.glb");
    let plan = write_campaign(&format!(
        "[\"{}\", {{ path = \"room_cm.obj\", up_axis = \"y\" }}, {{ path = \"room_*.obj\", unit_m = 0.001 }}]",
        apartment.display()
    ))
    .unwrap();
    let frames: Vec<(String, Option<&str>, Option<f64>)> = plan.takes[..6]
        .iter()
        .map(|t| {
            let name = t.scene.file_name().unwrap().to_string_lossy().into_owned();
            (name, t.up_axis.map(|u| u.name()), t.unit_m)
        })
        .collect();
    assert_eq!(
        frames,
        [
            ("apartment.glb".to_string(), None, None),
            ("room_cm.obj".to_string(), Some("y"), None),
            ("room_cm.obj".to_string(), None, Some(0.001)),
            ("plan_3.obj".to_string(), Some("z"), Some(1.0)),
            ("dwelling_1.glb".to_string(), Some("y"), Some(1.0)),
            ("dwelling_2.glb".to_string(), Some("y"), Some(1.0)),
        ]
    );
    let room_y_up = plan.takes[1].command(&plan.run, Path::new("t"));
    assert!(room_y_up.contains(" --up y"), "{room_y_up}");
    assert!(!room_y_up.contains("--unit-m"), "{room_y_up}");
    assert!(plan.takes[3]
        .command(&plan.run, Path::new("t"))
        .contains(" --up z --unit-m 1"));
    assert!(plan.takes[4]
        .command(&plan.run, Path::new("t"))
        .contains(" --up y --unit-m 1"));
    // The same file in two frames is two takes' definitions, with two ids.
    assert_ne!(plan.takes[1].id, plan.takes[2].id);

    // Bad entries are refused by entry and key, before anything is planned.
    for (scenes, says) in [
        (
            "[{ path = \"room_cm.obj\", unit_m = 0 }]",
            "campaign.scenes[0]`: `unit_m`",
        ),
        (
            "[\"room_cm.obj\", { path = \"room_cm.obj\", up_axis = \"x\" }]",
            "campaign.scenes[1]`: `up_axis`",
        ),
        (
            "[{ path = \"room_cm.obj\", units = 0.01 }]",
            "unknown key `units`",
        ),
        ("[{ up_axis = \"y\" }]", "`path` is missing"),
        ("[3]", "expected a path or a table"),
        (
            "[\"room_cm.obj\", \"nowhere_*.obj\"]",
            "campaign.scenes[1]`: \"nowhere_*.obj\" matches no file",
        ),
        ("[\"missing.obj\"]", "missing.obj is not a file"),
    ] {
        let err = write_campaign(scenes).map(|_| ()).unwrap_err();
        assert!(err.contains(says), "{scenes}: {err}");
    }
}

#[test]
fn a_campaign_s_seeds_stay_signed_64_bit_integers_to_the_last_take() {
    let root = common::repo_root();
    let dir = tempfile::tempdir().unwrap();
    let plan = |first_seed: u64| {
        let campaign = std::fs::read_to_string(root.join("configs/campaign.toml"))
            .unwrap()
            .replace("first_seed = 0", &format!("first_seed = {first_seed}"))
            .replace(
                "run = \"default.toml\"",
                &format!("run = \"{}/configs/default.toml\"", root.display()),
            )
            .replace("\"../", &format!("\"{}/", root.display()));
        let path = dir.path().join("campaign.toml");
        std::fs::write(&path, campaign).unwrap();
        egogen::campaign::plan_campaign(&path).map_err(|e| format!("{e:#}"))
    };
    // 12 takes: the last seed is first_seed + 11.
    let last = i64::MAX as u64;
    let p = plan(last - 11).unwrap();
    assert_eq!(p.takes[11].seed, last);
    let err = plan(last - 10).unwrap_err();
    assert!(
        err.contains("key `campaign.first_seed`: 9223372036854775797: the takes' seeds"),
        "{err}"
    );
    assert!(err.contains("must stay below 2^63"), "{err}");
}
