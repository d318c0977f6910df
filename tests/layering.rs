//! The module layering of `docs/ARCHITECTURE.md`, checked on the source: every `crate::x`
//! reference in code (comments aside) of module `m` must name a module `m` may use, in every
//! form (`crate::x::y`, `use crate::{x, y::z}`, braced groups across lines). A known
//! break is listed with why it is there; the test also fails when a listed break is gone, so
//! the list only shrinks.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// What each module may use (its own submodules aside). Lower layers first.
const ALLOWED: &[(&str, &[&str])] = &[
    // Files and numbers.
    ("math", &[]),
    ("paths", &[]),
    ("atomic_file", &[]),
    ("parser_guard", &[]),
    ("memory", &[]),
    ("npz", &[]),
    ("exr_file", &[]),
    ("progress", &[]),
    ("manifest", &["atomic_file"]),
    ("vertex_cache", &["atomic_file"]),
    // Things in the world.
    ("camera", &["math"]),
    ("body", &["math", "npz", "atomic_file"]),
    (
        "scene",
        &["math", "parser_guard", "atomic_file", "memory", "paths"],
    ),
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
    // One person walking: settings, observation, controllers, the judge and the step.
    (
        "walker",
        &["math", "body", "motion", "scene", "sensing", "atomic_file"],
    ),
    (
        "policy",
        &[
            "walker",
            "math",
            "memory",
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
            "walker",
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
            "body",
            "vertex_cache",
            "scene",
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
            "math",
            "body",
            "motion",
            "scene",
            "sensing",
            "policy",
            "walker",
            "synth",
            "preview",
            "atomic_file",
            "paths",
            "progress",
        ],
    ),
    ("inspect", &["exr_file", "preview", "math", "atomic_file"]),
    // Every output of a take beside its frame files: annotations, COLMAP, the manifest (through
    // one seam, fed by the finished take), the Aria streams (from trajectories).
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
            "exr_file",
            "inspect",
            "render",
            "motion",
            "synth",
            "body",
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
            "memory",
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
            "walker",
            "synth",
            "render",
            "inspect",
            "plan",
            "progress",
            "eval",
            "export",
        ],
    ),
    // Many takes of egogen-run's job through one pool, indexed.
    (
        "campaign",
        &[
            "atomic_file",
            "cli",
            "exr_file",
            "inspect",
            "preview",
            "manifest",
            "motion",
            "plan",
            "render",
            "run_job",
            "supervisor",
            "synth",
            "export",
            "scene",
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
    // The binaries' command lines: parse arguments and call any job.
    (
        "commands",
        &[
            "math",
            "paths",
            "atomic_file",
            "body",
            "scene",
            "rig",
            "motion",
            "walker",
            "synth",
            "render",
            "inspect",
            "eval",
            "export",
            "cli",
            "run_job",
            "campaign",
        ],
    ),
];

/// Breaks of the layering that exist today, as (module, what it uses, why); each is to be
/// removed. None today.
const KNOWN_BREAKS: &[(&str, &str, &str)] = &[];

/// Every `prefix::name` a Rust source refers to, with its 1-based line: plain paths
/// (`crate::scene::load`), and each top-level item of braced groups (`crate::{scene, rig::Rig}`),
/// across lines; line comments and doc comments aside.
fn references(text: &str, prefix: &str) -> Vec<(usize, String)> {
    let code: String = text
        .lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n");
    let ident = |s: &str| -> String {
        s.trim_start()
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let needle = format!("{prefix}::");
    let mut out = Vec::new();
    for (i, _) in code.match_indices(&needle) {
        // Only a path's start: not `other_crate::` or `self::crate::`.
        if code[..i]
            .chars()
            .next_back()
            .is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':')
        {
            continue;
        }
        let line = code[..i].matches('\n').count() + 1;
        let rest = &code[i + needle.len()..];
        if let Some(group) = rest.trim_start().strip_prefix('{') {
            // The top-level items of the group, up to its closing brace.
            let mut depth = 0;
            let mut item_start = 0;
            for (k, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth > 0 => depth -= 1,
                    ',' | '}' if depth == 0 => {
                        let name = ident(&group[item_start..k]);
                        if !name.is_empty() && name != "self" {
                            out.push((line, name));
                        }
                        item_start = k + 1;
                        if c == '}' {
                            break;
                        }
                    }
                    _ => {}
                }
            }
        } else {
            let name = ident(rest);
            if !name.is_empty() {
                out.push((line, name));
            }
        }
    }
    out
}

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

/// What a file of `module` uses (with its line) that is not in `may`, the layers below it.
fn upward_uses(module: &str, may: &BTreeSet<&str>, text: &str) -> Vec<(usize, String)> {
    references(text, "crate")
        .into_iter()
        .filter(|(_, used)| used != module && !may.contains(used.as_str()))
        .collect()
}

/// A planted upward import in the walker layer is found, and its own layers are not.
#[test]
fn a_planted_upward_import_in_the_walker_is_found() {
    let may: BTreeSet<&str> = ALLOWED
        .iter()
        .find(|(m, _)| *m == "walker")
        .expect("the walker is in the layering")
        .1
        .iter()
        .copied()
        .collect();
    let planted = "use crate::scene::SeenMap;\nuse crate::walker::state::Walker;\n\
                   use crate::policy::Actor;\nfn f() { crate::synth::crowd::run(); }\n";
    let up = upward_uses("walker", &may, planted);
    assert_eq!(
        up,
        [(3, "policy".to_string()), (4, "synth".to_string())],
        "the walker may not use what acts through it"
    );
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
        for (_, used) in references(&text, "crate") {
            if used != module {
                found.insert((module.clone(), used));
            }
        }
        for (line, used) in upward_uses(&module, may, &text) {
            if !known.contains(&(module.as_str(), used.as_str())) {
                problems.push(format!(
                    "{}:{line}: `{module}` uses `{used}`, which is not below it",
                    file.display()
                ));
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

/// Folders whose files still import each other in a circle, with why; each is to be undone,
/// and the test fails when one is gone (so the list only shrinks). None today.
const KNOWN_CYCLES: &[(&str, &str)] = &[];

/// The `.rs` files under `dir`, at any depth.
fn rust_files_under(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            files.extend(rust_files_under(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            files.push(p);
        }
    }
    files
}

/// An import cycle among the modules of one folder, if any: its files and its subfolders
/// with a `mod.rs` (a module split into files is one node: what its `mod.rs` reaches through
/// `super::x`, and what any of its files reaches through `crate::<folder>::x`); through
/// `super::x` and through `crate::<folder>::x` (the folder named from the crate's root,
/// `folder` as `render` or `motion::cvae`), in every form.
fn import_cycle(dir: &Path, folder: &str) -> Option<Vec<String>> {
    let own = format!("crate::{folder}");
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        let Some(name) = p.file_stem().map(|s| s.to_string_lossy().into_owned()) else {
            continue;
        };
        // (file, what `super::` means in it is this folder's sibling)
        let texts: Vec<(String, bool)> = if p.is_dir() && p.join("mod.rs").is_file() {
            rust_files_under(&p)
                .into_iter()
                .map(|f| {
                    let at_top = f == p.join("mod.rs");
                    (std::fs::read_to_string(f).unwrap(), at_top)
                })
                .collect()
        } else if p.extension().is_some_and(|x| x == "rs") && name != "mod" {
            vec![(std::fs::read_to_string(&p).unwrap(), true)]
        } else {
            continue;
        };
        let uses = graph.entry(name.clone()).or_default();
        for (text, supers_are_siblings) in &texts {
            let supers = match supers_are_siblings {
                true => references(text, "super"),
                false => Vec::new(),
            };
            for (_, used) in supers.into_iter().chain(references(text, &own)) {
                if used != name {
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
    graph
        .keys()
        .find_map(|n| visit(n, &graph, &mut Vec::new(), &mut done))
}

/// Every folder of `src/` (and its subfolders) whose files form no import cycle: inference
/// does not reach into evaluation or training code that reaches back, and so on; the folders
/// of [`KNOWN_CYCLES`] aside, which must still have theirs.
#[test]
fn no_folder_of_src_has_an_import_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut folders = vec![];
    let mut stack = vec![src.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            if e.path().is_dir() {
                stack.push(e.path());
                folders.push(e.path());
            }
        }
    }
    folders.sort();
    let mut problems = Vec::new();
    for dir in folders {
        let rel = dir
            .strip_prefix(Path::new(env!("CARGO_MANIFEST_DIR")))
            .unwrap()
            .display()
            .to_string();
        let folder = dir
            .strip_prefix(&src)
            .unwrap()
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join("::");
        let known = KNOWN_CYCLES.iter().find(|k| k.0 == rel);
        match (import_cycle(&dir, &folder), known) {
            (Some(c), None) => problems.push(format!("{rel}: import cycle {}", c.join(" → "))),
            (None, Some((_, why))) => problems.push(format!(
                "{rel} has no import cycle any more ({why}): remove it from KNOWN_CYCLES"
            )),
            _ => {}
        }
    }
    assert!(problems.is_empty(), "\n{}", problems.join("\n"));
}

/// A planted cycle of braced `super::{…}` imports is found.
#[test]
fn a_planted_cycle_is_found() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.rs"), "use super::{b::B, c};\n").unwrap();
    std::fs::write(dir.path().join("b.rs"), "use super::{\n    c::C,\n};\n").unwrap();
    std::fs::write(dir.path().join("c.rs"), "fn f() { super::a::g(); }\n").unwrap();
    assert_eq!(
        import_cycle(dir.path(), "x").unwrap(),
        ["a", "b", "c", "a"].map(String::from)
    );
    std::fs::write(dir.path().join("c.rs"), "// super::a::g();\n").unwrap();
    assert_eq!(import_cycle(dir.path(), "x"), None);
}

/// A module split into a folder is one node of its parent folder's graph: a cycle through a
/// file of it is found, and its own files' `super::` (the module itself) is no edge.
#[test]
fn a_planted_cycle_through_a_module_folder_is_found() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("b")).unwrap();
    std::fs::write(dir.path().join("a.rs"), "use super::b::run;\n").unwrap();
    std::fs::write(dir.path().join("b/mod.rs"), "mod part;\n").unwrap();
    std::fs::write(dir.path().join("b/part.rs"), "use super::helper;\n").unwrap();
    assert_eq!(import_cycle(dir.path(), "x"), None);
    std::fs::write(dir.path().join("b/part.rs"), "use crate::x::a::f;\n").unwrap();
    assert_eq!(
        import_cycle(dir.path(), "x").unwrap(),
        ["a", "b", "a"].map(String::from)
    );
}

/// A planted cycle through the folder's own name from the crate's root
/// (`crate::<folder>::…`, plain and braced) is found as one through `super::`.
#[test]
fn a_planted_cycle_through_the_folders_own_path_is_found() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.rs"), "use crate::render::b::B;\n").unwrap();
    std::fs::write(
        dir.path().join("b.rs"),
        "fn f() { crate::render::{\n    a::g,\n}(); }\n",
    )
    .unwrap();
    assert_eq!(
        import_cycle(dir.path(), "render").unwrap(),
        ["a", "b", "a"].map(String::from)
    );
    // Another folder's path of the same file names is no cycle of this one.
    assert_eq!(import_cycle(dir.path(), "scene"), None);
    // Nor a nested folder's: `crate::render::cvae::a` is not `crate::render::a`.
    std::fs::write(dir.path().join("b.rs"), "use crate::render::cvae::a;\n").unwrap();
    assert_eq!(import_cycle(dir.path(), "render"), None);
}

/// The reference reader sees every import form: a planted use of each form is found.
#[test]
fn every_import_form_is_seen() {
    let planted = "use crate::supervisor::run;\n\
                   use crate::{math::Vec3, supervisor};\n\
                   use crate::{\n    rig::{Rig, RigImu},\n    render,\n};\n\
                   fn f() { crate::eval::run(); }\n\
                   // crate::ignored_in_a_comment\n\
                   /// crate::ignored_in_docs\n\
                   use other_crate::not_ours;\n";
    let found: Vec<(usize, String)> = references(planted, "crate");
    let names: Vec<&str> = found.iter().map(|(_, n)| n.as_str()).collect();
    assert_eq!(
        names,
        ["supervisor", "math", "supervisor", "rig", "render", "eval"]
    );
    assert_eq!(
        found[3].0, 3,
        "a multi-line group is reported at its `crate::`"
    );
    let sup: Vec<String> = references("use super::{a, b::c};\nuse super::d;", "super")
        .into_iter()
        .map(|r| r.1)
        .collect();
    assert_eq!(sup, ["a", "b", "d"]);
}
