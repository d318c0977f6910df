//! A walker's step: how every walker judges the primitives its controller proposes and
//! chooses the one it takes — an episode of the training environment and of `egogen policy
//! eval` (`policy::env`), an agent of a take's crowd (`synth::crowd`: `egogen synth`,
//! `egogen-run`, the paper's Table 1). One [`Judge`] (limits, reward weights, the scene's 3-D
//! test) judges every decoded primitive; [`choose_primitive`] is the one function that
//! chooses: the best proposal by [`best_of`], then, with [`Redraws`], more
//! draws where the best walks into something (the policy's own, then the motion model's
//! prior), and, where every draw would take the pelvis over a wall, the body holding its
//! pose for a primitive.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;

use super::controller::{draw_action, Controller, Sight};
use super::reward::{
    judge, scene_penetration, Judged, Limits, RewardWeights, SceneTest, Situation,
};
use super::PosePrior;
use crate::body::joint;
use crate::math::random::normal_samples;
use crate::motion::cvae::infer::DecodeError;
use crate::motion::cvae::{BodyContext, DecodedPrimitive, MotionModel, PrimitiveSeed};
use crate::motion::primitive::SEED_FRAMES;
use crate::scene::SceneSdf;

/// Draws from the motion model's prior when every redraw of a primitive would take the pelvis
/// over a wall ([`Limits::scene_every_frame`]), before the body holds its pose.
pub(crate) const WALL_PRIOR_DRAWS: usize = 32;

/// How a primitive is tested against the scene's 3-D SDF, beside the walkable map's cells.
#[derive(Clone, Copy)]
pub(crate) enum SceneCheck<'a> {
    /// No 3-D test: the map's cells (and the swept test) alone.
    Cells,
    /// Training: Eq. 11 on a vertex subset decides penetration (beside the cells when
    /// `keeps_cells`).
    Fast {
        sdf: &'a SceneSdf,
        test: &'a SceneTest,
        keeps_cells: bool,
    },
    /// Evaluation: every vertex of every frame measured (Eq. 11); penetration by the cells.
    Measure { sdf: &'a SceneSdf },
}

/// The one set of limits and reward weights a walker's primitives are judged by.
pub(crate) struct Judge<'a> {
    pub limits: Limits,
    pub weights: RewardWeights,
    /// Primitives left before the walk times out after this one (the pace bonus's count).
    pub primitives_left: usize,
    pub foot_markers: &'a [usize],
    pub prior: &'a PosePrior,
    pub scene: SceneCheck<'a>,
    /// A primitive that penetrates earns no progress towards the goal (its goal term at most 0).
    pub no_progress_through_walls: bool,
}

impl Judge<'_> {
    /// `p` judged where the walker stands (`s`), and its reward as weighed (not finite where a
    /// term is not: [`finite_reward`] is what a walker adds up, while a controller's scores
    /// rank it last).
    pub(crate) fn judge(
        &self,
        body: &BodyContext,
        p: &DecodedPrimitive,
        s: &Situation,
    ) -> Result<(Judged, f64), DecodeError> {
        let mut j = judge(p, s, self.foot_markers, self.prior, &self.limits);
        match self.scene {
            SceneCheck::Cells => {}
            SceneCheck::Fast {
                sdf,
                test,
                keeps_cells,
            } => {
                let by_cells = keeps_cells && j.penetrated;
                j.set_penetrated(by_cells || test.penetrates(body, p, sdf)?);
            }
            SceneCheck::Measure { sdf } => {
                (j.scene_penetrating_frames, j.scene_vertices_inside_max) =
                    scene_penetration(body, p, sdf)?;
            }
        }
        if self.no_progress_through_walls && j.penetrated {
            j.terms.goal = j.terms.goal.min(0.0);
        }
        Ok((
            j,
            j.terms
                .total_with_arrival(&self.weights, self.primitives_left),
        ))
    }
}

/// A reward as a walker adds it up: 0 where it is not finite.
pub(crate) fn finite_reward(r: f64) -> f64 {
    if r.is_finite() {
        r
    } else {
        0.0
    }
}

/// Draws beyond the controller's proposals when the best of them walks into something (Eq. 7:
/// a wall, an obstacle, another person's box), steps into another person's box in any frame,
/// or ends with the pelvis off the walkable floor.
pub(crate) struct Redraws<'a> {
    /// Up to this many more actions from the policy's distribution (when given), then as many
    /// from the motion model's prior; the first that does none of these is taken, else one
    /// ending on the floor, else the one ending nearest to it, then the one with the fewest
    /// frames inside the others' boxes, then the one on the fewest blocked cells, then the one
    /// with the most room around its end. With the scene tested at every frame, a best that
    /// still takes the pelvis over a wall gets [`WALL_PRIOR_DRAWS`] more from the prior, and
    /// when all do, the body holds its pose for the primitive. 0: the best proposal as it is.
    pub count: usize,
    /// The policy's action distribution (mean, standard deviation) behind the proposal.
    pub policy: Option<(&'a [f32], &'a [f32])>,
}

/// One proposal decoded, judged and scored by its controller (higher is better; a score that
/// is not finite ranks last).
pub(crate) struct Proposal {
    pub latent: Vec<f32>,
    pub primitive: DecodedPrimitive,
    pub judged: Judged,
    /// [`finite_reward`] of the judge's.
    pub reward: f64,
    pub score: f64,
}

/// The primitive a walker takes.
#[derive(Debug, Clone)]
pub(crate) struct Chosen {
    pub latent: Vec<f32>,
    pub primitive: DecodedPrimitive,
    pub judged: Judged,
    pub reward: f64,
    /// The body holds its pose: every draw would have taken the pelvis over a wall.
    pub held: bool,
}

/// Where a walker's choice is made: the motion model and body that decode redraws, the seed
/// the primitive continues, the judge and the walker's situation.
pub(crate) struct StepContext<'a> {
    pub model: &'a MotionModel,
    pub body: &'a BodyContext<'a>,
    pub seed: &'a PrimitiveSeed,
    pub judge: &'a Judge<'a>,
    pub situation: &'a Situation<'a>,
    /// The walker's pelvis on the floor before the primitive.
    pub pelvis: DVec2,
}

/// The primitive a walker takes of its controller's `proposals` (decoded ones, in order):
/// the best by score ([`best_of`]), then, given `redraws` and the generator they draw from,
/// [`Redraws`] (none: the best proposal as it is, as training and EgoGen's protocol take it).
/// `None` when there is no proposal.
pub(crate) fn choose_primitive(
    ctx: &StepContext,
    proposals: Vec<Proposal>,
    redraws: Option<(&Redraws, &mut ChaCha8Rng)>,
) -> Result<Option<Chosen>, DecodeError> {
    let mut best: Option<Chosen> = best_of(proposals.into_iter().map(|p| {
        let score = Some(p.score);
        (
            Chosen {
                latent: p.latent,
                primitive: p.primitive,
                judged: p.judged,
                reward: p.reward,
                held: false,
            },
            score,
        )
    }));
    let Some((redraws, rng)) = redraws.filter(|(r, _)| r.count > 0) else {
        return Ok(best);
    };
    let map = ctx.situation.map;
    let swept = ctx.judge.limits.scene_every_frame;
    let l = ctx.model.latent_dim();
    let end_xy = |p: &DecodedPrimitive| {
        let end = p.joints[p.joints.len() - 1][joint::PELVIS];
        DVec2::new(end.x, end.y)
    };
    let off_floor = |p: &DecodedPrimitive| !map.is_walkable_at(end_xy(p));
    let rank = |p: &DecodedPrimitive, j: &Judged| {
        let room = map.sdf_at(end_xy(p));
        (
            // Swept: the fewest frames with the pelvis over a wall first.
            match swept {
                true => j.pelvis_off_floor_frames,
                false => 0,
            },
            off_floor(p),
            (-room).max(0.0),
            j.frames_in_obstacle,
            j.blocked_cells,
            -room,
        )
    };
    // A redraw judged and kept when it ranks better than the best so far.
    let offer = |best: &mut Option<Chosen>,
                 latent: Vec<f32>,
                 p: DecodedPrimitive|
     -> Result<(), DecodeError> {
        let (j, r) = ctx.judge.judge(ctx.body, &p, ctx.situation)?;
        if best
            .as_ref()
            .is_none_or(|b| rank(&p, &j) < rank(&b.primitive, &b.judged))
        {
            *best = Some(Chosen {
                latent,
                primitive: p,
                judged: j,
                reward: finite_reward(r),
                held: false,
            });
        }
        Ok(())
    };
    if let Some((mean, std)) = redraws.policy {
        // The policy's own draws first; then as many from the motion model's prior, whose
        // walks go every way (the way back when the policy's all lead on into a wall).
        for k in 0..2 * redraws.count {
            if best.as_ref().is_some_and(|b| {
                !b.judged.penetrated && !off_floor(&b.primitive) && b.judged.frames_in_obstacle == 0
            }) {
                break;
            }
            let z = if k < redraws.count {
                draw_action(mean, std, rng)
            } else {
                normal_samples(rng, l)
            };
            let p = match ctx.model.decode(
                ctx.body,
                std::slice::from_ref(ctx.seed),
                std::slice::from_ref(&z),
            ) {
                Ok(mut d) => d.remove(0),
                Err(DecodeError::NonFinite { .. }) => continue,
                Err(e) => return Err(e),
            };
            offer(&mut best, z, p)?;
        }
    }
    // Swept: a primitive whose pelvis would still pass over a wall is never taken. A batch of
    // the motion model's prior (turning and slow walks among them), then, when every draw
    // leads into the wall, the body holds its pose for a primitive.
    let crosses = |j: &Judged| swept && j.pelvis_off_floor_frames > 0;
    if map.is_walkable_at(ctx.pelvis) && best.as_ref().is_some_and(|b| crosses(&b.judged)) {
        let zs: Vec<Vec<f32>> = normal_samples(rng, WALL_PRIOR_DRAWS * l)
            .chunks(l)
            .map(<[f32]>::to_vec)
            .collect();
        let seeds = vec![ctx.seed.clone(); zs.len()];
        for (d, z) in ctx
            .model
            .decode_each(ctx.body, &seeds, &zs)?
            .into_iter()
            .zip(zs)
        {
            let p = match d {
                Ok(p) => p,
                Err(DecodeError::NonFinite { .. }) => continue,
                Err(e) => return Err(e),
            };
            offer(&mut best, z, p)?;
        }
        if let Some(b) = best.take_if(|b| crosses(&b.judged)) {
            let p = held(&b.primitive);
            let (j, r) = ctx.judge.judge(ctx.body, &p, ctx.situation)?;
            best = Some(Chosen {
                latent: b.latent,
                primitive: p,
                judged: j,
                reward: finite_reward(r),
                held: true,
            });
        }
    }
    Ok(best)
}

/// One walker's step: its controller's proposals ([`Controller::propose`]) decoded at the
/// walker's seed, judged, scored by the controller and chosen by [`choose_primitive`] with up
/// to `redraws` more draws. `None` when nothing decoded.
pub(crate) fn walk_step(
    controller: &mut dyn Controller,
    sight: &Sight,
    ctx: &StepContext,
    redraws: usize,
    rng: &mut ChaCha8Rng,
) -> Result<Option<Chosen>, DecodeError> {
    let proposed = controller.propose(sight, rng);
    let seeds = vec![ctx.seed.clone(); proposed.latents.len()];
    let decoded = ctx.model.decode_each(ctx.body, &seeds, &proposed.latents)?;
    let mut proposals = Vec::with_capacity(decoded.len());
    for (d, latent) in decoded.into_iter().zip(proposed.latents) {
        match d {
            Ok(p) => {
                let (j, r) = ctx.judge.judge(ctx.body, &p, ctx.situation)?;
                let score = controller.score(&p, &j, r);
                proposals.push(Proposal {
                    latent,
                    primitive: p,
                    judged: j,
                    reward: finite_reward(r),
                    score,
                });
            }
            Err(DecodeError::NonFinite { .. }) => {}
            Err(e) => return Err(e),
        }
    }
    let redraws = Redraws {
        count: redraws,
        policy: proposed
            .policy
            .as_ref()
            .map(|(mean, std)| (mean.as_slice(), std.as_slice())),
    };
    choose_primitive(ctx, proposals, Some((&redraws, rng)))
}

/// How [`choose_primitive`] ranks judged primitives: the one of highest score; a candidate that did not decode
/// (`None`) never beats one that did, a non-finite score counts as −∞, and among equals the
/// first is kept. `None` only when there is no candidate.
pub(crate) fn best_of<T>(candidates: impl IntoIterator<Item = (T, Option<f64>)>) -> Option<T> {
    let mut best: Option<(T, Option<f64>)> = None;
    for (candidate, score) in candidates {
        let score = score.map(|s| if s.is_finite() { s } else { f64::NEG_INFINITY });
        let better = match (&best, score) {
            (None, _) => true,
            (Some((_, None)), Some(_)) => true,
            (Some((_, Some(b))), Some(s)) => s > *b,
            (Some(_), None) => false,
        };
        if better {
            best = Some((candidate, score));
        }
    }
    best.map(|(candidate, _)| candidate)
}

/// `p` with its new frames all the seed's last frame: the body holding its pose for a
/// primitive (what a walker does when every draw would walk it through a wall).
fn held(p: &DecodedPrimitive) -> DecodedPrimitive {
    let mut h = p.clone();
    let last = SEED_FRAMES - 1;
    for k in SEED_FRAMES..h.world.len() {
        h.world[k] = h.world[last].clone();
        h.markers[k] = h.markers[last].clone();
        h.joints[k] = h.joints[last].clone();
        h.world_from_cpf[k] = h.world_from_cpf[last];
    }
    h
}

#[cfg(test)]
mod tests {
    use super::best_of;

    #[test]
    fn the_best_decoded_candidate_wins_and_the_first_among_equals() {
        assert_eq!(best_of(Vec::<(u8, Option<f64>)>::new()), None);
        // A candidate that did not decode never beats one that did, even one scoring below 0.
        assert_eq!(best_of([(0, Some(-5.0)), (1, None)]), Some(0));
        assert_eq!(best_of([(0, None), (1, Some(-5.0)), (2, None)]), Some(1));
        assert_eq!(best_of([(0, None), (1, None)]), Some(0));
        assert_eq!(
            best_of([(0, Some(1.0)), (1, Some(2.0)), (2, Some(2.0))]),
            Some(1)
        );
        // Non-finite scores count as −∞: any finite score beats them; among them the first.
        assert_eq!(best_of([(0, Some(f64::NAN)), (1, Some(-1e9))]), Some(1));
        assert_eq!(
            best_of([(0, Some(f64::NAN)), (1, Some(f64::INFINITY))]),
            Some(0)
        );
    }
}
