//! The module layering of `docs/ARCHITECTURE.md`, checked on the source: every `crate::x`
//! reference in code (comments aside) of module `m` must name a module `m` may use. A known
//! break is listed with why it is there; the test also fails when a listed break is gone, so
//! the list only shrinks.

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
    ("inspect", &["exr_file", "preview", "math", "atomic_file"]),
    // Checked run plans: made by cli, carried out by supervisor.
    ("plan", &["render", "rig", "camera", "math"]),
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

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn modules_use_only_the_layers_below_them() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let allowed: BTreeMap<&str, BTreeSet<&str>> = ALLOWED
        .iter()
        .map(|(m, deps)| (*m, deps.iter().copied().collect()))
        .collect();
    let known: BTreeSet<(&str, &str)> = KNOWN_BREAKS.iter().map(|(a, b, _)| (*a, *b)).collect();
    let mut files = Vec::new();
    rust_files(&src, &mut files);
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
