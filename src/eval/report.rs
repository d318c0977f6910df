//! Tables as markdown: one row per scenario and controller, the measures of
//! [`super::metrics::Row`] in the units a reader expects (%, m, m/s).

use super::metrics::Row;

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
pub fn table1_markdown(rows: &[Row], labels: &dyn Fn(&str) -> String) -> String {
    let mut md = String::from(
        "| scenario | controller | SR | Dist (m) | Cont | Pene-S | Pene-H | 2D overlap | Std (m) | left | cos(view, goal) | pose score | speed (m/s) | people × episodes | fell | wall (s) |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for r in rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} |\n",
            labels(&r.scenario),
            r.controller,
            pct(Some(r.success_rate)),
            num(Some(r.final_distance_m), 2),
            num(Some(r.contact), 3),
            pct(r.obstacle_penetration_share),
            pct(r.human_penetration_share),
            pct(r.human_overlap_share),
            num(r.path_std_m, 2),
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
