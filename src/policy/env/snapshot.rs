//! Episodes in progress as data: what training's checkpoints keep of an environment, and
//! how it is restored exactly.

use super::*;

/// An episode in progress as data (checkpoints of training).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct EpisodeSnapshot {
    id: u64,
    #[serde(default)]
    scene: Option<BoxParams>,
    #[serde(default)]
    crossing: Option<CrossingParams>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rooms: Option<RoomParams>,
    #[serde(default)]
    pair: Option<usize>,
    /// A generated dwelling's pair: the dwelling's index and the pair's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dwelling: Option<(usize, usize)>,
    /// The seed frames' pose (165) and translation (3).
    frames: Vec<Vec<f64>>,
    steps: usize,
    distance_m: f64,
    start_distance_m: f64,
    totals: Totals,
    /// What the walker has seen ([`SeenMap::to_bytes`]), where its guide plans on that.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    seen: Option<Vec<u8>>,
}

impl EpisodeSnapshot {
    /// The seed frames of the episode's next primitive: pose (165) and translation (3) each
    /// (what the environment's tests compare across a restore).
    #[cfg(test)]
    pub(crate) fn seed_frames(&self) -> &[Vec<f64>] {
        &self.frames
    }
}

/// All episodes in progress and the next episode's number.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct EnvSnapshot {
    pub episode_base: u64,
    pub next_episode: u64,
    pub episodes: Vec<EpisodeSnapshot>,
}

impl PolicyEnv<'_> {
    /// The episodes in progress as data.
    pub(crate) fn snapshot(&self) -> EnvSnapshot {
        EnvSnapshot {
            episode_base: self.episode_base,
            next_episode: self.next_episode,
            episodes: self
                .episodes
                .iter()
                .map(|e| EpisodeSnapshot {
                    id: e.id,
                    scene: e.course.box_params,
                    crossing: e.course.crossing.clone(),
                    rooms: e.course.rooms.clone(),
                    pair: e.course.pair,
                    dwelling: e.course.dwelling,
                    frames: e
                        .walker
                        .view
                        .seed
                        .frames
                        .iter()
                        .map(|f| f.pose.iter().copied().chain(f.transl.to_array()).collect())
                        .collect(),
                    steps: e.walker.steps,
                    distance_m: e.walker.distance_m,
                    start_distance_m: e.walker.start_distance_m,
                    totals: e.walker.totals.clone(),
                    seen: e.seen.as_ref().map(SeenMap::to_bytes),
                })
                .collect(),
        }
    }

    /// Continues from a snapshot of an environment of the same settings and size.
    pub(crate) fn restore(&mut self, snap: &EnvSnapshot) -> Result<(), EnvError> {
        if snap.episodes.len() != self.episodes.len() || snap.episode_base != self.episode_base {
            return Err(EnvError::Snapshot(format!(
                "{} episodes under base {} saved, {} under base {} here",
                snap.episodes.len(),
                snap.episode_base,
                self.episodes.len(),
                self.episode_base
            )));
        }
        let mut episodes = Vec::with_capacity(snap.episodes.len());
        for s in &snap.episodes {
            if s.frames.len() != SEED_FRAMES || s.frames.iter().any(|f| f.len() != POSE_DIM + 3) {
                return Err(EnvError::Snapshot(format!(
                    "episode {}: seed frames of the wrong size",
                    s.id
                )));
            }
            let frames: [BodyParams; SEED_FRAMES] = std::array::from_fn(|k| {
                let f = &s.frames[k];
                BodyParams {
                    pose: std::array::from_fn(|i| f[i]),
                    transl: Vec3::new(f[POSE_DIM], f[POSE_DIM + 1], f[POSE_DIM + 2]),
                    ..BodyParams::default()
                }
            });
            let only_fixed = self.fixed.is_some() && self.settings.fixed_share >= 1.0;
            let dwelling_of = |(d, pair): (usize, usize)| {
                self.dwellings
                    .get(d)
                    .is_some_and(|f| pair < f.pairs.len())
                    .then_some((d, pair))
            };
            let course = match (
                s.scene,
                s.crossing.clone(),
                s.rooms.clone(),
                s.pair,
                self.fixed,
                s.dwelling.map(dwelling_of),
            ) {
                (None, None, None, None, _, Some(Some((d, pair)))) => self.dwelling_course(d, pair),
                (_, _, _, _, _, Some(_)) => {
                    return Err(EnvError::Snapshot(format!(
                        "episode {}: its dwelling is not one of this environment's",
                        s.id
                    )))
                }
                (Some(p), None, None, None, _, None) if !only_fixed => {
                    self.box_course(BoxScene::build(&self.settings.scene, p))
                }
                (None, Some(c), None, None, _, None) if !only_fixed => {
                    self.crossing_course(CrossingScene::build(&self.settings.crossing, c))
                }
                (None, None, Some(r), None, _, None) if !only_fixed => {
                    self.room_course(RoomScene::build(&self.settings.rooms, r))
                }
                (None, None, None, Some(pair), Some(f), None) if pair < f.pairs.len() => {
                    self.fixed_course(f, pair)
                }
                _ => {
                    return Err(EnvError::Snapshot(format!(
                        "episode {}: its scene is not of this environment's kind",
                        s.id
                    )))
                }
            };
            let floor_z = course.map.floor_z_m;
            let view = SeedView::new(self.body, PrimitiveSeed { frames, floor_z })?;
            let remembers = self.remembers(&course);
            let seen = match (&s.seen, remembers) {
                (Some(bytes), true) => {
                    Some(SeenMap::from_bytes(&course.map, bytes).ok_or_else(|| {
                        EnvError::Snapshot(format!(
                            "episode {}: its memory does not fit its map",
                            s.id
                        ))
                    })?)
                }
                (None, false) => None,
                _ => {
                    return Err(EnvError::Snapshot(format!(
                        "episode {}: saved {} a memory, its walker here {}",
                        s.id,
                        if s.seen.is_some() { "with" } else { "without" },
                        if remembers { "remembers" } else { "does not" }
                    )))
                }
            };
            episodes.push(Episode {
                id: s.id,
                seen,
                course,
                walker: Walker {
                    view,
                    steps: s.steps,
                    distance_m: s.distance_m,
                    start_distance_m: s.start_distance_m,
                    totals: s.totals.clone(),
                },
            });
        }
        self.episodes = episodes;
        self.next_episode = snap.next_episode;
        Ok(())
    }
}
