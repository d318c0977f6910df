//! Where an episode walks — a box scene, a crossing, a floor plan, a pair of a fixed scene or
//! of a generated dwelling — drawn per episode from its own generator, with the weights and
//! time it is judged by.

use super::*;

/// Where an episode walks: its walkable map, the obstacle of a box scene, start and goal.
#[derive(Debug, Clone)]
pub(super) struct Course {
    pub(super) map: Arc<WalkableMap>,
    pub(super) obstacle: Option<Obstacle2>,
    /// Obstacles that move, on the episode's clock.
    pub(super) moving: Vec<MovingObstacle>,
    pub(super) start: DVec2,
    pub(super) goal: DVec2,
    /// What was drawn: a box scene, or a pair of a fixed scene.
    pub(super) box_params: Option<BoxParams>,
    pub(super) crossing: Option<CrossingParams>,
    pub(super) rooms: Option<RoomParams>,
    pub(super) pair: Option<usize>,
    /// A generated dwelling's pair: the dwelling's index and the pair's.
    pub(super) dwelling: Option<(usize, usize)>,
    /// Primitives before the episode times out.
    pub(super) max_primitives: usize,
    /// The scene's 3D SDF, where Eq. 11 is measured.
    pub(super) sdf: Option<Arc<SceneSdf>>,
    /// The walking distance to the goal, with [`EnvSettings::goal_by_path`] indoors.
    pub(super) goal_field: Option<Arc<PathField>>,
    /// The walking distance from start to goal, found once when first asked
    /// ([`Course::way_round_m`]).
    pub(super) way_round: std::sync::OnceLock<Option<f64>>,
}

/// A fixed scene (e.g. the apartment) and the start/goal pairs its episodes walk, in turn.
#[derive(Debug, Clone)]
pub(crate) struct FixedScene {
    pub map: Arc<WalkableMap>,
    pub pairs: Vec<StartGoal>,
    /// The scene's 3D SDF, where scene penetration is measured (paper Eq. 11; evaluation
    /// only: posing and looking up every vertex of every frame made the apartment evaluation
    /// about 30× slower, docs/POLICY.md).
    pub sdf: Option<Arc<SceneSdf>>,
}

/// Where an episode walks, for pictures: its map, its still and moving obstacles (on the
/// episode's clock), its start and goal.
#[derive(Debug, Clone)]
pub(crate) struct CourseView {
    pub map: Arc<WalkableMap>,
    pub obstacle: Option<Obstacle2>,
    pub moving: Vec<MovingObstacle>,
    pub start: DVec2,
    pub goal: DVec2,
}

/// One episode in progress.
#[derive(Debug, Clone)]
pub(super) struct Episode {
    pub(super) id: u64,
    pub(super) course: Course,
    pub(super) walker: Walker,
    /// What the walker has seen, where its guide plans on that ([`WalkerSettings::guide_memory`]).
    pub(super) seen: Option<SeenMap>,
}

impl Course {
    /// Whether the course is indoors: a floor plan, a pair of the fixed scene or of a
    /// generated dwelling.
    pub(super) fn indoors(&self) -> bool {
        self.rooms.is_some() || self.pair.is_some() || self.dwelling.is_some()
    }

    /// The walking distance from the start to the goal round what blocks walking on the map
    /// (indoors only: a box scene's box and a crossing's person are not on the map).
    pub(super) fn way_round_m(&self) -> Option<f64> {
        *self.way_round.get_or_init(|| {
            if !self.indoors() {
                return None;
            }
            match &self.goal_field {
                Some(f) => f.at(self.start),
                None => PathField::to_goal(&self.map, self.goal)?.at(self.start),
            }
        })
    }

    pub(super) fn surroundings(&self) -> Surroundings<'_> {
        Surroundings {
            map: &self.map,
            obstacle: self.obstacle.as_ref(),
            moving: &self.moving,
        }
    }
}

impl PolicyEnv<'_> {
    /// The reward weights of an episode on `course`.
    pub(super) fn weights(&self, course: &Course) -> RewardWeights {
        let changes = if course.indoors() {
            &self.settings.indoor_weights
        } else if course.box_params.is_some() {
            &self.settings.box_weights
        } else {
            return self.settings.weights;
        };
        changes.applied_to(self.settings.weights)
    }

    pub(super) fn box_course(&self, scene: BoxScene) -> Course {
        Course {
            map: Arc::new(scene.map),
            obstacle: Some(scene.obstacle),
            moving: Vec::new(),
            start: scene.start,
            goal: scene.goal,
            box_params: Some(scene.params),
            crossing: None,
            rooms: None,
            pair: None,
            dwelling: None,
            max_primitives: self.settings.walker.max_primitives_per_goal,
            sdf: None,
            goal_field: None,
            way_round: Default::default(),
        }
    }

    pub(super) fn room_course(&self, scene: RoomScene) -> Course {
        self.timed_for_way_round(Course {
            obstacle: None,
            moving: Vec::new(),
            start: scene.start,
            goal: scene.goal,
            box_params: None,
            crossing: None,
            rooms: Some(scene.params),
            pair: None,
            dwelling: None,
            max_primitives: self.settings.rooms.max_primitives,
            sdf: None,
            goal_field: self.goal_field(&scene.map, scene.goal),
            way_round: Default::default(),
            map: Arc::new(scene.map),
        })
    }

    pub(super) fn crossing_course(&self, scene: CrossingScene) -> Course {
        Course {
            map: self.crossing_floor.clone(),
            obstacle: None,
            moving: scene.movers,
            start: scene.start,
            goal: scene.goal,
            box_params: None,
            crossing: Some(scene.params),
            rooms: None,
            pair: None,
            dwelling: None,
            max_primitives: self.settings.walker.max_primitives_per_goal,
            sdf: None,
            goal_field: None,
            way_round: Default::default(),
        }
    }

    pub(super) fn fixed_course(&self, f: &FixedScene, pair: usize) -> Course {
        let max_primitives = self
            .settings
            .fixed_max_primitives
            .unwrap_or(self.settings.walker.max_primitives_per_goal);
        self.timed_for_way_round(Course {
            pair: Some(pair),
            ..self.pair_course(f, pair, max_primitives)
        })
    }

    /// Pair `pair` of generated dwelling `d` of the training config's `[dwellings]`.
    pub(super) fn dwelling_course(&self, d: usize, pair: usize) -> Course {
        let max_primitives = self.settings.dwellings.max_primitives;
        self.timed_for_way_round(Course {
            dwelling: Some((d, pair)),
            ..self.pair_course(&self.dwellings[d], pair, max_primitives)
        })
    }

    /// Pair `pair` of scene `f`, not yet said whose (a fixed scene's or a dwelling's) nor timed.
    fn pair_course(&self, f: &FixedScene, pair: usize, max_primitives: usize) -> Course {
        Course {
            map: f.map.clone(),
            obstacle: None,
            moving: Vec::new(),
            start: f.pairs[pair].start,
            goal: f.pairs[pair].goal,
            box_params: None,
            crossing: None,
            rooms: None,
            pair: None,
            dwelling: None,
            max_primitives,
            sdf: f.sdf.clone(),
            goal_field: self.goal_field(&f.map, f.pairs[pair].goal),
            way_round: Default::default(),
        }
    }

    /// An indoor course with time for its way round walls, when the settings ask for it
    /// ([`EnvSettings::time_by_way_round_m`]).
    pub(super) fn timed_for_way_round(&self, mut course: Course) -> Course {
        let per_primitive = self.settings.time_by_way_round_m;
        if per_primitive > 0.0 {
            if let Some(way) = course.way_round_m() {
                let needed = (way / per_primitive).ceil();
                if needed.is_finite() && needed > course.max_primitives as f64 {
                    course.max_primitives = needed as usize;
                }
            }
        }
        course
    }

    /// The walking-distance field of an indoor goal, when the settings ask for one.
    pub(super) fn goal_field(&self, map: &WalkableMap, goal: DVec2) -> Option<Arc<PathField>> {
        self.settings
            .goal_by_path
            .then(|| PathField::to_goal(map, goal).map(Arc::new))
            .flatten()
    }

    /// The course of episode `id`: the next pair of the fixed scene (or, with a fixed share
    /// below 1, a random pair for that share of episodes), else a random pair of a generated
    /// dwelling (with the dwellings' share), else a new floor plan (with the rooms' share),
    /// else a new crossing scene (with the crossing share) or box scene.
    pub(super) fn draw_course(&self, id: u64, rng: &mut ChaCha8Rng) -> Course {
        let crossing = self.settings.crossing;
        let rooms = self.settings.rooms;
        let share = self.settings.fixed_share;
        match self.fixed {
            // No draw when only the fixed scene is walked: evaluations stay as they were.
            Some(f) if share >= 1.0 => self.fixed_course(f, (id % f.pairs.len() as u64) as usize),
            Some(f) if uniform_open01(rng) < share => {
                self.fixed_course(f, (rng.next_u64() % f.pairs.len() as u64) as usize)
            }
            // No draw when no episode walks a dwelling: runs without them stay as they were.
            _ if self.settings.dwellings.share > 0.0
                && !self.dwellings.is_empty()
                && uniform_open01(rng) < self.settings.dwellings.share =>
            {
                let d = (rng.next_u64() % self.dwellings.len() as u64) as usize;
                let pair = (rng.next_u64() % self.dwellings[d].pairs.len() as u64) as usize;
                self.dwelling_course(d, pair)
            }
            // No draw when there are no floor plans: runs without them stay as they were.
            _ if rooms.share > 0.0 && uniform_open01(rng) < rooms.share => {
                self.room_course(RoomScene::sample(&rooms, rng))
            }
            // No draw when there are no crossings: box-only runs stay as they were.
            _ if crossing.share > 0.0 && uniform_open01(rng) < crossing.share => {
                self.crossing_course(CrossingScene::sample(&crossing, rng))
            }
            _ => self.box_course(BoxScene::sample(&self.settings.scene, rng)),
        }
    }
}
