//! What an environment is asked for: its scenes and their shares, the reward weights, the
//! walker's settings over the paper's preset, and what ends an episode.

use super::*;

/// Settings of the environment (defaults: EgoGen's box pretraining).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvSettings {
    pub scene: BoxSceneSettings,
    /// Crossing scenes (another person walking across the path) and their share of episodes.
    pub crossing: CrossingSettings,
    /// Procedural floor plans (rooms, doorways, furniture) and their share of episodes.
    pub rooms: RoomSettings,
    /// Furnished generated dwellings (the config's `[dwellings]`) and their share of episodes.
    pub dwellings: DwellingShare,
    pub weights: RewardWeights,
    /// Changes to `weights` in box-scene episodes (e.g. a stronger cost for looking off the
    /// goal where a box stands in the open). Nothing given: `weights`.
    pub box_weights: WeightChanges,
    /// Changes to `weights` in the indoor episodes, floor plans and the fixed scene's pairs
    /// (e.g. a pace bonus where paths bend round walls). Nothing given: `weights`.
    pub indoor_weights: WeightChanges,
    /// How the walker of every episode steps (`[stages.env.walker]`, the one schema of
    /// [`WalkerSettings`]; keys left out are the paper's, [`WalkerSettings::PAPER`]): the goal
    /// reached within `success_m`, an episode timing out after `max_primitives_per_goal`
    /// primitives (EgoGen's box scenes: 11), the scene tested at every frame or at a
    /// primitive's end, the others seen ahead (`anticipate_people`), the guide round what hides
    /// the goal (`guide_*`; with [`Self::guide_indoors_only`], indoor episodes alone). An
    /// episode takes its controller's best proposal as it is and writes no motion:
    /// `penetration_redraws`, `smooth_joins` and `steady_head` stay off (training configs are
    /// refused otherwise).
    #[serde(deserialize_with = "paper_walker")]
    pub walker: WalkerSettings,
    /// Evaluation as the paper's tables: `Some(r)` ends an episode (and pays the success
    /// term) only when the pelvis comes within `r` m, and an episode that times out within
    /// `success_m` still succeeds — walks go on to EgoGen's goal threshold and are scored at
    /// the tables' radius. `None` (default): both at `success_m`.
    pub arrival_m: Option<f64>,
    /// End the episode when the body penetrates (fine-tuning).
    pub terminate_on_penetration: bool,
    /// Blocked cells in the body's 2D box beyond which it penetrates (paper Eq. 7: 3).
    pub penetration_cells: usize,
    /// Whether a body marker inside another person's box in any frame of a primitive
    /// penetrates too (Eq. 7 looks at the primitive's last frame only, and a person crossing
    /// at 1 m/s moves 0.45 m within one); false: Eq. 7 alone, as EgoGen.
    pub people_every_frame: bool,
    /// Whether a body marker inside a box scene's box in any frame of a primitive penetrates
    /// too (the eval's penetration measure; Eq. 7 looks at the primitive's last frame only);
    /// false: Eq. 7 alone, as EgoGen.
    pub box_every_frame: bool,
    /// With the guide on: only indoor episodes (floor plans and the fixed scene's pairs) are
    /// guided; box scenes and crossings walk to their goals unguided, as the paper's tables
    /// evaluate them. false: every episode.
    pub guide_indoors_only: bool,
    /// Largest angle between the seed's facing and the goal direction (rad; EgoGen's box
    /// environment: 0.2π).
    pub seed_yaw_jitter_rad: f64,
    /// Whether indoor episodes (floor plans and the fixed scene's pairs) pay the goal term by
    /// the walking distance round walls (`scene::PathField`), orientation and attention facing
    /// the way it leads, instead of by the straight distance (not EgoGen's: a training signal
    /// for goals behind walls; observations, success and evaluation measures stay straight).
    pub goal_by_path: bool,
    /// Whether a primitive that penetrates earns no progress towards the goal (its goal term
    /// at most 0): paid along the way round walls, one step through a wall would otherwise
    /// gain the whole way round at once. false: the goal term as measured, as EgoGen.
    pub no_progress_through_walls: bool,
    /// With a fixed scene: the share of episodes that walk one of its pairs (drawn at random),
    /// the others box scenes and crossings as without one; 1 walks only its pairs, in turn.
    pub fixed_share: f64,
    /// Primitives before an episode in the fixed scene times out (EgoGen's apartment: 13);
    /// `None`: `walker.max_primitives_per_goal`.
    pub fixed_max_primitives: Option<usize>,
    /// With N > 0, penetration in a fixed scene with a 3D SDF is paper Eq. 11 on N body
    /// vertices ([`crate::walker::reward::SceneTest`]) instead of Eq. 7 (EgoGen's apartment): the
    /// termination and the penetration reward term. 0: Eq. 7 everywhere.
    pub scene_test_vertices: usize,
    /// With `scene_test_vertices`: Eq. 7's cells still count there too, a primitive penetrating
    /// when either test says so.
    pub scene_test_keeps_cells: bool,
    /// With M > 0, an indoor episode (a floor plan or a pair of the fixed scene) has time for
    /// its way round walls: at least `way round / M` primitives (e.g. 7/13 m: the time 13
    /// primitives give a 7 m straight walk), never fewer than its own limit. 0: the limit
    /// alone, as EgoGen.
    pub time_by_way_round_m: f64,
}

impl Default for EnvSettings {
    fn default() -> Self {
        Self {
            scene: BoxSceneSettings::default(),
            crossing: CrossingSettings::default(),
            rooms: RoomSettings::default(),
            dwellings: DwellingShare::default(),
            weights: RewardWeights::default(),
            box_weights: WeightChanges::default(),
            indoor_weights: WeightChanges::default(),
            walker: WalkerSettings::PAPER,
            arrival_m: None,
            terminate_on_penetration: false,
            penetration_cells: crate::walker::reward::EQ7_PENETRATION_CELLS,
            people_every_frame: false,
            box_every_frame: false,
            guide_indoors_only: false,
            seed_yaw_jitter_rad: 0.2 * std::f64::consts::PI,
            goal_by_path: false,
            no_progress_through_walls: false,
            fixed_share: 1.0,
            fixed_max_primitives: None,
            scene_test_vertices: 0,
            scene_test_keeps_cells: false,
            time_by_way_round_m: 0.0,
        }
    }
}

/// How many episodes walk a pair of the training config's generated dwellings
/// (`[stages.env.dwellings]`; the dwellings and their pairs are the config's `[dwellings]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DwellingShare {
    /// Share of the episodes outside the fixed scene that walk a pair of a generated dwelling
    /// (0, default: none); the floor plans' and crossings' shares apply to the rest.
    pub share: f64,
    /// Primitives before such an episode times out (default 13, the apartment's).
    pub max_primitives: usize,
}

impl Default for DwellingShare {
    fn default() -> Self {
        Self {
            share: 0.0,
            max_primitives: 13,
        }
    }
}

/// `[stages.env.walker]` over the paper's preset.
fn paper_walker<'de, D: serde::Deserializer<'de>>(d: D) -> Result<WalkerSettings, D::Error> {
    WalkerSettings::over(WalkerSettings::PAPER, d)
}
