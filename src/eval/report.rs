//! `RESULTS.md`: every table of the result files in `results/` as markdown (Table 1 one row
//! per scenario and controller, the measures of [`super::metrics::Row`] in the units a reader
//! expects: %, m, m/s), the paper's tables beside them, and the notes that say how each was
//! run and measured.

use std::path::Path;

use anyhow::Result;

use super::files::{read_json, KeptRows, PolicyRow, PolicyRowsFile, RowsFile};
use super::metrics::Row;
use super::scenarios::Scenario;

fn pct(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{:.1} %", 100.0 * v))
}

fn num(v: Option<f64>, digits: usize) -> String {
    match v {
        Some(v) if v.is_finite() => format!("{v:.digits$}"),
        _ => "–".into(),
    }
}

/// Table 1 as a markdown table (header included).
pub(crate) fn table1_markdown(rows: &[Row], labels: &dyn Fn(&str) -> String) -> String {
    let mut md = String::from(
        "| scenario | controller | SR | Dist (m) | Cont | Pene-S | Pene-H capsules | Pene-H mesh | 2D overlap | Std (m) | at each time (m) | pooled (m) | left | cos(view, goal) | pose score | speed (m/s) | people × episodes | fell | wall (s) |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for r in rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} |\n",
            labels(&r.scenario),
            r.controller,
            pct(Some(r.success_rate)),
            num(Some(r.final_distance_m), 2),
            num(Some(r.contact), 3),
            pct(r.obstacle_penetration_share),
            pct(r.human_penetration_share),
            pct(r.human_mesh_penetration_share),
            pct(r.human_overlap_share),
            num(r.path_std_m, 2),
            num(r.path_location_std_m, 2),
            num(r.path_pooled_std_m, 2),
            pct(r.path_left_share),
            num(Some(r.view_cos), 3),
            num(Some(r.pose_score), 2),
            num(r.speed_successful_m_s, 2),
            r.people,
            r.fallen,
            r.wall_s,
        ));
    }
    md
}

/// What `--keep-other-rows` kept, for the table's header: nothing when it kept nothing. Rows
/// are named by controller, with the scenarios of each (once for all when they share them).
fn kept_rows_markdown(kept: &[KeptRows]) -> String {
    let code = |names: &[&str]| {
        names
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    kept.iter()
        .filter(|k| !k.rows.is_empty())
        .map(|k| {
            let mut by_controller: Vec<(&str, Vec<&str>)> = Vec::new();
            for key in &k.rows {
                let (scenario, controller) = key.split_once('/').unwrap_or((key, ""));
                match by_controller.iter_mut().find(|(c, _)| *c == controller) {
                    Some((_, scenarios)) => scenarios.push(scenario),
                    None => by_controller.push((controller, vec![scenario])),
                }
            }
            let shared = by_controller.windows(2).all(|w| w[0].1 == w[1].1);
            let rows = if shared {
                let controllers: Vec<&str> = by_controller.iter().map(|(c, _)| *c).collect();
                format!(
                    "The {} rows of {}",
                    code(&controllers),
                    code(&by_controller[0].1)
                )
            } else {
                let each: Vec<String> = by_controller
                    .iter()
                    .map(|(c, scenarios)| format!("`{c}` of {}", code(scenarios)))
                    .collect();
                format!("The rows {}", each.join("; "))
            };
            format!(
                " {rows} are kept from an earlier run (`--keep-other-rows`): `{}`, policy `{}`, \
                 {:.0} s of wall time for all its rows.",
                k.command, k.policy, k.wall_s
            )
        })
        .collect()
}

/// A scenario's label in the tables (its name where none is known).
fn scenario_label(name: &str) -> String {
    Scenario::table1()
        .iter()
        .find(|s| s.name() == name)
        .map_or(name.to_string(), |s| s.label())
}

/// `RESULTS.md` from the result files in `out/results` (those present).
pub(crate) fn results_markdown(out: &Path) -> Result<String> {
    let results = out.join("results");
    let mut md = String::from(
        "# Results: the paper's evaluation on egogen\n\n\
         Written by `egogen eval` from the files in `results/` — do not edit by hand; each \
         table names the command that reproduces it, and `egogen eval --suite report --out \
         docs` rewrites this file from them alone. Wall times are of the machine that ran it \
         (2 cores; episodes run two at a time).\n\n",
    );
    md.push_str(&paper_beside_markdown(&results)?);
    if let Some(t) = read_json::<RowsFile>(&results.join("table1.json"))? {
        let labels = scenario_label;
        md.push_str(&format!(
            "## Table 1: avoiding moving obstacles and other people\n\n```\n{}\n```\n\n\
             {} episodes per row, seed {}, policy `{}`, K = {} latents per primitive for the \
             sampling controller and the path-following baseline; {:.0} s of wall time.{}\n\n",
            t.command,
            t.episodes,
            t.seed,
            t.policy,
            t.k.map_or("?".into(), |k| k.to_string()),
            t.wall_s,
            kept_rows_markdown(&t.kept),
        ));
        md.push_str(&table1_markdown(&t.rows, &labels));
        md.push_str(TABLE1_NOTES);
        md.push_str("\n### Paths (episode 0; every episode of the static box)\n");
        let mut last = String::new();
        for r in &t.rows {
            let file = format!("table1_{}_{}.png", r.scenario, r.controller);
            if !results.join(&file).is_file() {
                continue;
            }
            if r.scenario != last {
                md.push_str(&format!("\n**{}**\n\n", labels(&r.scenario)));
                last = r.scenario.clone();
            }
            md.push_str(&format!(
                "![{} {}](results/{file})\n",
                r.scenario, r.controller
            ));
        }
        md.push('\n');
    }
    if let Some(t) = read_json::<RowsFile>(&results.join("speed.json"))? {
        md.push_str(&format!(
            "## Speed and accuracy: the policy against sampling with K latents\n\n```\n{}\n```\n\n\
             {} episodes per row, seed {}, policy `{}`; {:.0} s of wall time. Wall per episode \
             is the episode's own time (two episodes run at once on the 2 cores); the ratio is \
             to the policy with sampled actions in the same scenario.\n\n",
            t.command, t.episodes, t.seed, t.policy, t.wall_s
        ));
        md.push_str(&speed_markdown(&t.rows, &scenario_label));
        md.push('\n');
    }
    if let Some(t) = read_json::<PolicyRowsFile>(&results.join("rays.json"))? {
        md.push_str(&knob_markdown(
            "Rays per scan",
            "differing only in the rays of their scan (`[policy.sensing] num_rays`, same ±90° \
             fan and 7 m)",
            &t,
        ));
    }
    if let Some(t) = read_json::<PolicyRowsFile>(&results.join("width.json"))? {
        md.push_str(&knob_markdown(
            "Policy width",
            "differing only in the width of their networks (`[policy] hidden` = H: GRU \
             encoders H wide, actor and critic MLPs 2H + 4F; EgoGen's is 512)",
            &t,
        ));
    }
    if let Some(t) = read_json::<PolicyRowsFile>(&results.join("sdf.json"))? {
        md.push_str(&sdf_markdown(&t));
    }
    if let Some(t) = read_json::<PolicyRowsFile>(&results.join("table2.json"))? {
        md.push_str(&table2_markdown(&t));
    }
    if let Some(t) = read_json::<PolicyRowsFile>(&results.join("table3.json"))? {
        md.push_str(&format!(
            "## Table 3: ablations\n\n```\n{}\n```\n\n\
             Each policy trained from scratch with the budget of `configs/train_policy.toml` \
             (2.0 M environment steps, seed 0; the shipped policy is that run's, fine-tuned \
             further in the apartment, docs/POLICY.md), evaluated on the first {} held-out box \
             scenes and crossings (seed {}; walks going on to 0.1 m, success within 0.3 m where they end, 11 \
             primitives, episodes not \
             ended by penetration); {:.0} s of wall time.\n\n",
            t.command, t.episodes, t.seed, t.wall_s
        ));
        md.push_str(&box_rows_markdown(
            &t.rows,
            "speed, successful (median)",
            &|r| format!("{:.2} m/s", r.speed_successful_median_m_s),
        ));
        md.push_str(TABLE3_NOTES);
    }
    Ok(md)
}

/// The paper's Tables 1–3 beside ours (those of the results in `results/`).
fn paper_beside_markdown(results: &Path) -> Result<String> {
    let mut md = String::from(
        "## The paper beside ours\n\n\
         The paper's Tables 1–3 (EgoGen, CVPR 2024) with our figures of the tables below beside \
         them, each line saying whether ours is measured the paper's way or ours (and how, \
         under each table).\n\n",
    );
    if let Some(t) = read_json::<RowsFile>(&results.join("table1.json"))? {
        md.push_str("### Table 1\n\n");
        md.push_str(&crate::eval::paper::table1_beside(&t.rows));
        md.push('\n');
    }
    if let Some(t) = read_json::<PolicyRowsFile>(&results.join("table2.json"))? {
        md.push_str("### Table 2\n\n");
        md.push_str(&crate::eval::paper::table2_beside(&t.rows));
        md.push('\n');
    }
    if let Some(t) = read_json::<PolicyRowsFile>(&results.join("table3.json"))? {
        md.push_str("### Table 3\n\n");
        md.push_str(&crate::eval::paper::table3_beside(
            &t.rows,
            t.pose_norm.as_ref(),
        ));
        md.push('\n');
    }
    Ok(md)
}

/// The speed suite's rows of a knob (`title`) whose policies differ as `differing` says.
fn knob_markdown(title: &str, differing: &str, t: &PolicyRowsFile) -> String {
    let mut md = format!(
        "### {title}\n\nThe same run: policies trained with the budget and settings of \
         `configs/train_policy.toml` (2.0 M environment steps, seed 0), {differing}, on the \
         first {} held-out box scenes and crossings (walks going on to 0.1 m, success within 0.3 m where they \
         end, 11 primitives, 50 \
         episodes at once); {:.0} s. Wall: the row's episodes, one decode batch of 50 at a \
         time.\n\n",
        t.episodes, t.wall_s
    );
    md.push_str(&box_rows_markdown(&t.rows, "wall (s)", &|r| {
        format!("{:.2}", r.wall_s)
    }));
    md.push('\n');
    md
}

/// Rows of policies on box scenes and crossings, `last` naming the column before the config.
fn box_rows_markdown(
    rows: &[PolicyRow],
    last: &str,
    value: &dyn Fn(&PolicyRow) -> String,
) -> String {
    let mut md = format!(
        "| policy | set | actions | success | foot contact | penetration | cos(view, goal) | final distance (median) | {last} | trained by |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n"
    );
    for r in rows {
        md.push_str(&format!(
            "| {} | {} | {} | {:.1} % | {:.3} | {:.2} % | {:.3} | {:.2} m | {} | `{}` |\n",
            r.policy,
            r.set,
            r.actions,
            100.0 * r.success_rate,
            r.contact,
            100.0 * r.penetration_share,
            r.view_cos,
            r.final_distance_median_m,
            value(r),
            r.config
        ));
    }
    md
}

/// The speed suite's SDF-resolution rows.
fn sdf_markdown(t: &PolicyRowsFile) -> String {
    let mut md = format!(
        "### SDF resolution\n\nThe same run: the shipped policy (mean action) on Table 2's \
         first {} apartment pairs, scene penetration (paper Eq. 11: ≥ 40 of 13 380 vertices \
         inside the scene) measured on the apartment's 3D SDF at each voxel size; {:.0} s. \
         Set-up: loading the scene, drawing the pairs and building the SDF; wall: the \
         episodes, 50 at once.\n\n\
         | SDF voxel | scene penetration (Eq. 11) | success | set-up (s) | wall (s) |\n\
         | --- | --- | --- | --- | --- |\n",
        t.episodes, t.wall_s
    );
    for r in &t.rows {
        md.push_str(&format!(
            "| {} | {:.2} % | {:.1} % | {:.1} | {:.1} |\n",
            r.set.trim_start_matches("apartment, SDF voxel "),
            100.0 * r.scene_penetration_share.unwrap_or(f64::NAN),
            100.0 * r.success_rate,
            r.setup_s.unwrap_or(f64::NAN),
            r.wall_s
        ));
    }
    md.push('\n');
    md
}

/// Table 2's section of `RESULTS.md`.
fn table2_markdown(t: &PolicyRowsFile) -> String {
    use super::suite::{TABLE2_MAX_PRIMITIVES, TABLE2_PAIR_DISTANCE_M, TABLE2_SCENE};
    let (lo, hi) = TABLE2_PAIR_DISTANCE_M;
    let mut md = format!(
        "## Table 2: egocentric sensing against a local map (the apartment)\n\n```\n{}\n```\n\n\
         The first {} held-out start/goal pairs {lo}–{hi} m apart inside the walls of \
         `{TABLE2_SCENE}` (seed {}; 0.4 m from anything blocking), {TABLE2_MAX_PRIMITIVES} \
         primitives per walk as EgoGen's apartment, walks going on to 0.1 m, success \
         within 0.3 m where they end; {:.0} s of wall \
         time. The apartment is closed: the ground around its walls is blocked in the map \
         the walker senses, as `egogen synth` has it; only the doors-closed policy and those \
         that continue it (the floor-plan rows, the shipped one among them, and the Eq. 11 \
         rows) were fine-tuned \
         so (the others learnt the apartment with its outer doors open). The first three \
         policies were trained with the same recipe and budget — the box-and-crossing \
         stages, then the apartment stages (2.0 M + 0.8 M environment steps) — and differ \
         only in what they observe (`[policy.sensing]`): the paper's 32 rays over ±90°, 7 m, \
         or a body-centred occupancy patch reaching 0.8 m (16 × 16 cells of 0.1 m, DIMOS's \
         walkability map) or 7 m (32 × 32 cells of 0.44 m) in every direction. The guided \
         row is not the paper's method: where a wall hides the goal, the walker is shown the \
         point 2 m along an A* path round it instead (docs/POLICY.md, \"A guide round \
         walls\"); EgoGen's 95 % is without a path.\n\n",
        t.command, t.episodes, t.seed, t.wall_s
    );
    md.push_str(
        "| policy | actions | success | final distance (mean / median) | foot contact | scene penetration (Eq. 11) | cos(view, goal) | speed, successful (median) | trained by |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n\
         | EgoGen (paper Tab. 2), egocentric sensing | | 95 % | 0.12 m | | | | | |\n",
    );
    for r in &t.rows {
        md.push_str(&format!(
            "| {} | {} | {:.1} % | {:.2} / {:.2} m | {:.3} | {} | {:.3} | {:.2} m/s | `{}` |\n",
            r.policy,
            r.actions,
            100.0 * r.success_rate,
            r.final_distance_mean_m.unwrap_or(f64::NAN),
            r.final_distance_median_m,
            r.contact,
            r.scene_penetration_share
                .map_or("–".into(), |v| format!("{:.2} %", 100.0 * v)),
            r.view_cos,
            r.speed_successful_median_m_s,
            r.config
        ));
    }
    md.push_str(
        "\nScene penetration: share of frames with at least 40 of the body's 13 380 vertices \
         inside the scene (negative 3D SDF, paper Eq. 11). Foot contact: paper Eq. 12 with 3-D \
         foot-marker speed. The baselines use no policy: the sampling controller keeps the \
         best of K latents by the reward, the A* path follower (GAMMA*/DIMOS* in spirit) the \
         one that follows a path planned on the walkable map, replanned every primitive; the \
         latter walks through the crowd stepping of Table 1 (its own seed poses; Eq. 11 not \
         measured). The paper's rows: \"The paper beside ours\" above.\n\n",
    );
    md
}

const TABLE3_NOTES: &str = "
Penetration: share of frames with a body marker inside the box's or the other person's
footprint. Foot contact: paper Eq. 12 with 3-D foot-marker speed. The egocentric-depth policy
observes a 16 × 32 depth image ray cast from the same world as the rays, through a small CNN
(docs/POLICY.md, \"Network\"), the others the paper's 32 rays. The paper's rows: \"The
paper beside ours\" above.
";

/// The speed suite's rows: accuracy beside the wall time per episode and its ratio to the
/// policy's (sampled actions) in the same scenario.
fn speed_markdown(rows: &[crate::eval::metrics::Row], labels: &dyn Fn(&str) -> String) -> String {
    let mut md = String::from(
        "| scenario | controller | SR | Dist (m) | Cont | Pene-S | Pene-H | wall per episode (s) | × policy |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let pct = |v: Option<f64>| v.map_or("–".into(), |v| format!("{:.1} %", 100.0 * v));
    for r in rows {
        let per = r.wall_s / r.episodes.max(1) as f64;
        let policy = rows
            .iter()
            .find(|p| p.scenario == r.scenario && p.controller == "policy")
            .map(|p| p.wall_s / p.episodes.max(1) as f64);
        md.push_str(&format!(
            "| {} | {} | {} | {:.2} | {:.3} | {} | {} | {:.2} | {} |\n",
            labels(&r.scenario),
            r.controller,
            pct(Some(r.success_rate)),
            r.final_distance_m,
            r.contact,
            pct(r.obstacle_penetration_share),
            pct(r.human_penetration_share),
            per,
            policy.map_or("–".into(), |p| format!("{:.2}", per / p)),
        ));
    }
    md
}

const TABLE1_NOTES: &str = "
Scenarios (`src/eval/scenarios.rs`), each on an open 14 × 14 m floor, starts on the held-out
mocap clips' seed poses: **moving obstacle** — one person walks 5 m; a box of side 0.5–1 m
crosses the line at right angles (± 30°) at 0.5–1 m/s through a point 35–65 % of the way,
timed to meet a walker at 0.7 m/s (± 1 s); **N people** — evenly on a circle (random phase),
each walking to the opposite point, as EgoGen's `main_crowd_eval.py`, each seeing the others
where they will stand when its primitive ends (egogen's crowd stepping, docs/SYNTH.md, 'Seeing
the others ahead'; `--controllers policy_as_placed,policy_mean_as_placed` adds the policy in
EgoGen's loop, the others where they were last put); **static box** — one
person walks 5 m along the x axis past a 1 × 1 m box at the midpoint, the same scene every
episode. Each person may take as many primitives as the longest walk needs at 0.5 m/s, plus
2 s.

A walk to a goal ends when the pelvis comes within 0.1 m of it (the paper's goal threshold,
where its environment ends an episode) or when the person's primitives run out.

Measures (`src/eval/metrics.rs`), means over every person of every episode: **SR** pelvis
within 0.3 m of the goal where the walk ends; **Dist** final pelvis–goal distance; **Cont**
paper Eq. 12 with 3-D foot-marker speed (EgoGen's and DIMOS's code); **Pene-S** share of
frames with a body marker inside an obstacle's footprint; **Pene-H** share of person-frames
(every 4th frame) with a body vertex inside another body: inside its volume modelled as
capsules along the skeleton's bones with radius the median skin distance (`body::volume`, a
lower bound), and inside its posed mesh (exact: winding number, `body::occupancy`); **2D
overlap** share of person-frames with a marker inside another person's 2D box (what the
policy senses); **Std** the standard deviation over episodes of the lateral offset from the
start–goal line at 9 stations (10–90 % of the way), averaged; **at each time** and
**pooled** the paper's \"standard deviation of pelvis locations\" read two ways (\"The paper
beside ours\" above); **left** the share of walks passing the box on the left; **cos** between the viewing direction and the goal
direction at primitive ends; **pose score** the pose prior's −ln p / 63 (lower is more
plausible; its limit is −0.874, docs/POLICY.md); **speed** of the people who reached the
goal; **wall** the row's episodes' wall times summed (two episodes run at once, so the row
took about half of it).

Controllers: **policy** actions sampled from the shipped policy, **policy_mean** its mean
action; **sampling_kK** the best of K random latents by the training reward; **path_follow_kK**
the baseline in the spirit of GAMMA*/DIMOS*: an A* path on the 0.1 m walkable grid around
the other people's current 2D boxes and the moving obstacles where they stand (0.3 m
clearance), replanned every primitive, and of K random latents the one whose primitive ends
nearest the point 0.8 m ahead on it (+1 m for a primitive that penetrates). Same motion
model, no policy.
";

#[cfg(test)]
mod tests {
    use super::*;

    fn kept(rows: &[&str]) -> KeptRows {
        KeptRows {
            command: "egogen eval --suite table1 --out docs".into(),
            policy: "assets/policy/rooms/policy.safetensors".into(),
            wall_s: 3035.4,
            rows: rows.iter().map(|r| r.to_string()).collect(),
        }
    }

    #[test]
    fn kept_rows_are_named_by_controller_once_for_shared_scenarios() {
        let shared = kept_rows_markdown(&[kept(&[
            "circle_2/sampling_k16",
            "circle_2/path_follow_k16",
            "static_box/sampling_k16",
            "static_box/path_follow_k16",
        ])]);
        assert!(
            shared.contains(
                "The `sampling_k16`, `path_follow_k16` rows of `circle_2`, `static_box` are kept"
            ),
            "{shared}"
        );
        assert!(shared.contains("3035 s of wall time"), "{shared}");
        let apart = kept_rows_markdown(&[kept(&[
            "circle_2/sampling_k16",
            "static_box/sampling_k16",
            "static_box/path_follow_k16",
        ])]);
        assert!(
            apart.contains(
                "The rows `sampling_k16` of `circle_2`, `static_box`; `path_follow_k16` of \
                 `static_box` are kept"
            ),
            "{apart}"
        );
        // Nothing kept, nothing said.
        assert_eq!(kept_rows_markdown(&[]), "");
        assert_eq!(kept_rows_markdown(&[kept(&[])]), "");
    }
}
