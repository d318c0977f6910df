//! The module layering of `docs/ARCHITECTURE.md`, checked on the source: every `crate::x`
//! reference in code (comments aside) of module `m` must name a module `m` may use. A known
//! break is listed with why it is there; the test also fails when a listed break is gone, so
//! the list only shrinks.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// What each module may use (its own submodules aside). Lower layers first.
const ALLOWED: &[(&str, &[&str])] = &[
    // Files and numbers.
    ("math", &[]),
    ("paths", &[]),
    ("atomic_file", &[]),
    ("parser_guard", &[]),
    ("npz", &[]),
    ("exr_file", &[]),
    ("progress", &[]),
    ("manifest", &["atomic_file"]),
    ("vertex_cache", &["atomic_file"]),
    // Things in the world.
    ("camera", &["math"]),
    ("body", &["math", "npz", "atomic_file"]),
    ("scene", &["math", "parser_guard", "atomic_file"]),
    ("rig", &["math", "camera", "atomic_file"]),
    ("sensing", &["math", "scene"]),
    ("preview", &["math", "scene", "atomic_file"]),
    // Motion and control.
    (
        "motion",
        &[
            "math",
            "body",
            "npz",
            "atomic_file",
            "parser_guard",
            "paths",
            "progress",
        ],
    ),
    (
        "policy",
        &[
            "math",
            "body",
            "motion",
            "scene",
            "sensing",
            "atomic_file",
            "paths",
            "progress",
        ],
    ),
    // Making a sequence, rendering it, looking at it.
    (
        "synth",
        &[
            "math",
            "body",
            "motion",
            "scene",
            "sensing",
            "policy",
            "preview",
            "manifest",
            "atomic_file",
            "npz",
            "vertex_cache",
            "progress",
        ],
    ),
    (
        "render",
        &[
            "math",
            "camera",
            "rig",
            "exr_file",
            "atomic_file",
            "paths",
            "npz",
        ],
    ),
    // The paper's tables: scenarios walked by synth, measured.
    (
        "eval",
        &[
            "math", "body", "motion", "scene", "sensing", "policy", "synth", "preview",
        ],
    ),
    ("inspect", &["exr_file", "preview", "math", "atomic_file"]),
    // Outputs made from a finished take's trajectories (Aria streams).
    (
        "export",
        &[
            "math",
            "camera",
            "rig",
            "scene",
            "atomic_file",
            "manifest",
            "preview",
        ],
    ),
    // Checked run plans: made by cli, carried out by supervisor.
    (
        "plan",
        &[
            "render", "rig", "camera", "math", "scene", "synth", "export",
        ],
    ),
    // Turning a run plan into a dataset.
    (
        "supervisor",
        &[
            "math",
            "paths",
            "atomic_file",
            "npz",
            "exr_file",
            "manifest",
            "vertex_cache",
            "camera",
            "body",
            "scene",
            "rig",
            "motion",
            "synth",
            "render",
            "inspect",
            "preview",
            "plan",
            "progress",
            "export",
        ],
    ),
    // Configs and commands: may use everything but the supervisor.
    (
        "cli",
        &[
            "math",
            "paths",
            "atomic_file",
            "npz",
            "exr_file",
            "manifest",
            "vertex_cache",
            "parser_guard",
            "camera",
            "body",
            "scene",
            "rig",
            "sensing",
            "preview",
            "motion",
            "policy",
            "synth",
            "render",
            "inspect",
            "plan",
            "progress",
            "eval",
            "export",
        ],
    ),
    // egogen-run's job: a config (cli) through the supervisor to a dataset.
    (
        "run_job",
        &[
            "body",
            "cli",
            "motion",
            "plan",
            "supervisor",
            "synth",
            "export",
        ],
    ),
];

/// Breaks of the layering that exist today, as (module, what it uses, why); each is to be
/// removed. None today.
const KNOWN_BREAKS: &[(&str, &str, &str)] = &[];

fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

#[test]
fn modules_use_only_the_layers_below_them() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let allowed: BTreeMap<&str, BTreeSet<&str>> = ALLOWED
        .iter()
        .map(|(m, deps)| (*m, deps.iter().copied().collect()))
        .collect();
    let known: BTreeSet<(&str, &str)> = KNOWN_BREAKS.iter().map(|(a, b, _)| (*a, *b)).collect();
    let files = common::files_with_extension(&src, "rs");
    let mut found: BTreeSet<(String, String)> = BTreeSet::new();
    let mut problems = Vec::new();
    for file in files {
        let module = module_of(&src, &file);
        if module == "bin" || module == "lib" {
            continue;
        }
        let Some(may) = allowed.get(module.as_str()) else {
            problems.push(format!(
                "{}: module `{module}` is not in the layering (add it to tests/layering.rs and docs/ARCHITECTURE.md)",
                file.display()
            ));
            continue;
        };
        let text = std::fs::read_to_string(&file).unwrap();
        for (n, line) in text.lines().enumerate() {
            let code = line.trim_start();
            if code.starts_with("//") {
                continue;
            }
            for (i, _) in code.match_indices("crate::") {
                let used: String = code[i + 7..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if used.is_empty() || used == module {
                    continue;
                }
                found.insert((module.clone(), used.clone()));
                if !may.contains(used.as_str())
                    && !known.contains(&(module.as_str(), used.as_str()))
                {
                    problems.push(format!(
                        "{}:{}: `{module}` uses `{used}`, which is not below it",
                        file.display(),
                        n + 1
                    ));
                }
            }
        }
    }
    for (a, b, why) in KNOWN_BREAKS {
        if !found.contains(&(a.to_string(), b.to_string())) {
            problems.push(format!(
                "known break {a} → {b} ({why}) is gone: remove it from KNOWN_BREAKS"
            ));
        }
    }
    assert!(problems.is_empty(), "\n{}", problems.join("\n"));
}

/// Files of one folder that reference each other through `super::x` form no cycle: inference
/// does not reach into evaluation or training code that reaches back.
fn assert_no_cycle(folder: &str) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(folder);
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for e in std::fs::read_dir(&dir).unwrap().flatten() {
        let p = e.path();
        let Some(name) = p.file_stem().map(|s| s.to_string_lossy().into_owned()) else {
            continue;
        };
        if p.extension().is_none_or(|x| x != "rs") || name == "mod" {
            continue;
        }
        let text = std::fs::read_to_string(&p).unwrap();
        let uses = graph.entry(name.clone()).or_default();
        for line in text.lines().filter(|l| !l.trim_start().starts_with("//")) {
            for (i, _) in line.match_indices("super::") {
                let used: String = line[i + 7..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if !used.is_empty() && used != name {
                    uses.insert(used);
                }
            }
        }
    }
    // Depth-first search for a back edge.
    fn visit(
        n: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|p| p == n) {
            let mut cycle = path[at..].to_vec();
            cycle.push(n.to_string());
            return Some(cycle);
        }
        if done.contains(n) {
            return None;
        }
        path.push(n.to_string());
        for m in graph.get(n).into_iter().flatten() {
            if graph.contains_key(m) {
                if let Some(c) = visit(m, graph, path, done) {
                    return Some(c);
                }
            }
        }
        path.pop();
        done.insert(n.to_string());
        None
    }
    let mut done = BTreeSet::new();
    for n in graph.keys() {
        if let Some(c) = visit(n, &graph, &mut Vec::new(), &mut done) {
            panic!("{folder}: import cycle {}", c.join(" → "));
        }
    }
}

#[test]
fn the_motion_model_files_form_no_import_cycle() {
    assert_no_cycle("src/motion/cvae");
    assert_no_cycle("src/policy");
}
