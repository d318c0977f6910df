//! The one schema of a walker's settings: how every walker steps — the `[walker]` table of
//! synth and run configs (and so of every campaign take), a training stage's
//! `[stages.env.walker]` (over the paper's preset, [`WalkerSettings::PAPER`]) and the flags of
//! `egogen policy eval` — with its defaults and its checks. A new walker setting is a field
//! here (its doc comment, its default, its check in [`WalkerSettings::problem`]) and the code
//! that reads it.

use serde::{Deserialize, Serialize};

use crate::scene::Guide;

/// How a walker steps (`[walker]`; docs/SYNTH.md "Walker settings"). Unknown keys are refused.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WalkerSettings {
    /// A goal is reached when the pelvis comes this close (m, horizontal; default 0.3).
    pub success_m: f64,
    /// Primitives a walker spends on one goal before it is missed (default 20).
    pub max_primitives_per_goal: usize,
    /// When the chosen primitive walks into something — more than 3 blocked cells under the
    /// body's 2D box at its end (paper Eq. 7: walls, obstacles, the others' boxes), a body
    /// marker inside another person's box or an obstacle in any frame, the pelvis ending off
    /// the walkable floor — up to this many more actions are drawn from the policy, then as
    /// many from the motion model's prior (`walker::step`; default 4; 0: none, as trained).
    pub penetration_redraws: usize,
    /// Where a wall hides the goal, the policy is shown the point this far (m) along the
    /// shortest path round what blocks the straight way (`scene::guide_aim`; rewards and
    /// success stay the goal's). Default 1 (with `guide_memory`: the way round what the
    /// walker has seen; docs/SYNTH.md "In a real house never walked"); 0: the goal itself, as
    /// EgoGen (and `guide_memory` then does nothing).
    pub guide_lookahead_m: f64,
    /// With a guide: it plans only on what the walker's own rays have shown it so far in the
    /// take (`scene::SeenMap`, kept from goal to goal; default true) instead of on the whole
    /// walkable map (false: a map the walker is given).
    pub guide_memory: bool,
    /// With a guide: how strongly its path keeps to the middle of doorways and corridors
    /// (`scene::plan_path_centred`; 0, default: the shortest path at its clearance).
    pub guide_centre_weight: f64,
    /// With a guide on memory: how much dearer a step onto ground the walker never saw is
    /// than one onto ground seen open (`scene::Guide::unknown_cost`; 0, default: the unknown
    /// taken as open).
    pub guide_unknown_cost: f64,
    /// `true` (default): the walker sees each other person where that person will stand when
    /// its primitive ends and judges its primitive against them moving; `false`: both where
    /// they were last put (EgoGen's crowd loop; docs/SYNTH.md "Seeing the others ahead").
    pub anticipate_people: bool,
    /// `true` (default): every primitive is tested against the scene at every frame it spans
    /// (no step passes through a wall); `false`: at its end alone (EgoGen's test).
    pub scene_every_frame: bool,
    /// `true` (default): where one primitive hands over to the next (or to an activity, or to
    /// a held pose), the velocity jump is spread over ±0.2 s (`motion::joins`); `false`: the
    /// primitives as decoded, a jolt at every join (docs/MOTION.md "Head motion").
    pub smooth_joins: bool,
    /// `true` (default): the neck and head turn against the torso's sway so the heading of the
    /// gaze follows its smoothed course (`motion::head_stabilise`); `false`: the head as
    /// decoded, swaying with the body.
    pub steady_head: bool,
    /// `true` (default): the fingers move with what the hands do — relaxed while walking and
    /// standing, resting when seated, opening and closing round what is picked up — each
    /// person's hands its own (`motion::hands`; docs/HANDS.md); `false`: the body model's
    /// rest hand on every frame (hand pose all zeros).
    pub finger_motion: bool,
}

impl Default for WalkerSettings {
    fn default() -> Self {
        Self {
            success_m: 0.3,
            max_primitives_per_goal: 20,
            penetration_redraws: 4,
            guide_lookahead_m: 1.0,
            guide_memory: true,
            guide_centre_weight: 0.0,
            guide_unknown_cost: 0.0,
            anticipate_people: true,
            scene_every_frame: true,
            smooth_joins: true,
            steady_head: true,
            finger_motion: true,
        }
    }
}

impl WalkerSettings {
    /// EgoGen's walker, as the paper trains and evaluates it: the goal reached within 0.1 m,
    /// 11 primitives to reach it (its box scenes), no redraws, no guide, the others where they
    /// were last put, the scene tested at a primitive's end, the motion as decoded. What a
    /// training stage's `[stages.env.walker]` starts from.
    pub(crate) const PAPER: WalkerSettings = WalkerSettings {
        success_m: 0.1,
        max_primitives_per_goal: 11,
        penetration_redraws: 0,
        guide_lookahead_m: 0.0,
        guide_memory: false,
        guide_centre_weight: 0.0,
        guide_unknown_cost: 0.0,
        anticipate_people: false,
        scene_every_frame: false,
        smooth_joins: false,
        steady_head: false,
        finger_motion: false,
    };

    /// A key a training stage's `[stages.env.walker]` set that only a take reads, if any, and
    /// why training has no use for it: an episode takes its controller's best proposal as it
    /// is and writes no motion.
    pub(crate) fn take_only_given(&self) -> Option<(&'static str, &'static str)> {
        let paper = WalkerSettings::PAPER;
        [
            (
                "penetration_redraws",
                self.penetration_redraws != paper.penetration_redraws,
                "an episode takes its controller's best proposal as it is",
            ),
            (
                "smooth_joins",
                self.smooth_joins,
                "an episode writes no motion: the joins are smoothed where a take writes it",
            ),
            (
                "steady_head",
                self.steady_head,
                "an episode writes no motion: the head is steadied where a take writes it",
            ),
            (
                "finger_motion",
                self.finger_motion,
                "an episode writes no motion: the fingers move where a take writes it",
            ),
        ]
        .into_iter()
        .find(|(_, given, _)| *given)
        .map(|(key, _, why)| (key, why))
    }

    /// The keys given in a table (`given`, e.g. a config's `[stages.env.walker]`) over
    /// `preset`: what a key left out is. Unknown keys are refused, naming them.
    pub(crate) fn over<'de, D: serde::Deserializer<'de>>(
        preset: WalkerSettings,
        given: D,
    ) -> Result<WalkerSettings, D::Error> {
        use serde::de::Error;
        // TOML values (not JSON): a NaN given stays one, for `problem` to name.
        let given = toml::Table::deserialize(given)?;
        let mut table = toml::Table::try_from(preset).map_err(D::Error::custom)?;
        for (k, v) in given {
            if !table.contains_key(&k) {
                return Err(D::Error::custom(format!(
                    "unknown walker setting `{k}`, expected one of {}",
                    Self::keys().join(", ")
                )));
            }
            table.insert(k, v);
        }
        WalkerSettings::deserialize(toml::Value::Table(table)).map_err(D::Error::custom)
    }

    /// The guide these settings give a policy-steered walker (`guide_*`).
    pub(crate) fn guide(&self) -> Guide {
        Guide {
            lookahead_m: self.guide_lookahead_m,
            centre_weight: self.guide_centre_weight,
            unknown_cost: self.guide_unknown_cost,
        }
    }

    /// Whether the walker remembers what its rays saw: its guide plans on that.
    pub(crate) fn remembers(&self) -> bool {
        self.guide_memory && self.guide_lookahead_m > 0.0
    }

    /// EgoGen's walker: no guide (the goal itself, whatever hides it), the rest as these.
    pub(crate) fn unguided(self) -> Self {
        Self {
            guide_lookahead_m: 0.0,
            guide_memory: false,
            guide_centre_weight: 0.0,
            guide_unknown_cost: 0.0,
            ..self
        }
    }

    /// What is wrong with these settings, if anything: the key (a config key's last part; a
    /// flag is it with dashes) and what was expected. One check for `[walker]`, training
    /// configs and `egogen policy eval`. Memory without a guide is no mistake here (it is on by
    /// default, and `guide_lookahead_m = 0` turns the guide off); see [`Self::problem_over`].
    pub(crate) fn problem(&self) -> Option<(&'static str, String)> {
        self.problem_over(&WalkerSettings::default())
    }

    /// [`Self::problem`] for settings given over `preset`: memory turned on against the preset
    /// without a guide to plan on it is a mistake too.
    pub(crate) fn problem_over(&self, preset: &WalkerSettings) -> Option<(&'static str, String)> {
        let memory = match self.guide_memory != preset.guide_memory {
            true => self.guide_memory,
            false => self.remembers(),
        };
        if let Some(p) = guide_problem(&self.guide(), memory) {
            return Some(p);
        }
        if !(self.success_m.is_finite() && self.success_m > 0.0) {
            return Some((
                "success_m",
                format!("expected a radius > 0 m, got {}", self.success_m),
            ));
        }
        if self.max_primitives_per_goal == 0 {
            return Some((
                "max_primitives_per_goal",
                "expected a whole number ≥ 1, got 0".into(),
            ));
        }
        None
    }

    /// The keys whose values differ from the defaults (what a config set), in alphabetical order.
    pub(crate) fn changed_keys(&self) -> Vec<String> {
        let table = |s: &WalkerSettings| match serde_json::to_value(s) {
            Ok(serde_json::Value::Object(m)) => m,
            _ => serde_json::Map::new(),
        };
        let default = table(&WalkerSettings::default());
        table(self)
            .into_iter()
            .filter(|(k, v)| default.get(k) != Some(v))
            .map(|(k, _)| k)
            .collect()
    }

    /// Whether every setting is its default (a config that sets none).
    pub(crate) fn is_default(&self) -> bool {
        *self == WalkerSettings::default()
    }

    /// Every key of the schema.
    pub(crate) fn keys() -> Vec<String> {
        match serde_json::to_value(WalkerSettings::default()) {
            Ok(serde_json::Value::Object(m)) => m.into_iter().map(|(k, _)| k).collect(),
            _ => Vec::new(),
        }
    }
}

/// What is wrong with a guide's settings, if anything: the setting's name and what was
/// expected.
fn guide_problem(guide: &Guide, memory: bool) -> Option<(&'static str, String)> {
    let Guide {
        lookahead_m,
        centre_weight,
        unknown_cost,
    } = *guide;
    if !(lookahead_m.is_finite() && lookahead_m >= 0.0) {
        return Some((
            "guide_lookahead_m",
            format!("expected a distance ≥ 0 m, got {lookahead_m}"),
        ));
    }
    if !(centre_weight.is_finite() && centre_weight >= 0.0) {
        return Some((
            "guide_centre_weight",
            format!("expected a weight ≥ 0, got {centre_weight}"),
        ));
    }
    if !(unknown_cost.is_finite() && unknown_cost >= 0.0) {
        return Some((
            "guide_unknown_cost",
            format!("expected a weight ≥ 0, got {unknown_cost}"),
        ));
    }
    let needs_lookahead = |what: &str| {
        format!("a guide {what} only with a lookahead > 0 m (e.g. 1 or 2): give one too")
    };
    if lookahead_m == 0.0 && memory {
        return Some(("guide_memory", needs_lookahead("plans on memory")));
    }
    if lookahead_m == 0.0 && centre_weight > 0.0 {
        return Some((
            "guide_centre_weight",
            needs_lookahead("keeps to the middle of doorways"),
        ));
    }
    if unknown_cost > 0.0 && !memory {
        return Some((
            "guide_unknown_cost",
            "a cost of unseen ground applies only to a guide that plans on the walker's memory: \
             turn memory on too (with a lookahead > 0 m)"
                .into(),
        ));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changed_keys_name_what_differs_from_the_defaults() {
        assert!(WalkerSettings::default().changed_keys().is_empty());
        let s = WalkerSettings {
            guide_lookahead_m: 2.0,
            anticipate_people: false,
            ..Default::default()
        };
        assert_eq!(s.changed_keys(), ["anticipate_people", "guide_lookahead_m"]);
        assert_eq!(WalkerSettings::keys().len(), 12);
        assert!(WalkerSettings::PAPER.problem().is_none());
        assert!(WalkerSettings::keys().contains(&"scene_every_frame".to_string()));
    }
}
