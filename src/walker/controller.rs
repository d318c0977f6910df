//! What proposes a walker's next primitive: the `Controller` trait, its three kinds (the
//! trained policy, the best of K random latents, the path-planning baseline) and the one serde
//! spec they are built from ([`ControllerSpec`]: reports' and `egogen eval`'s controller
//! names; a config's `steering` name is a [`Steering`], made into a spec with its `k` and
//! `action_spread`). A controller proposes latents; `walker::step::walk_step` decodes,
//! judges and chooses among them the same way for every kind. A new controller is one type
//! here with its `Controller` impl, its arm in [`ControllerSpec`] and its [`Steering`] variant;
//! takes and `egogen policy eval --controller` then use it.

use glam::DVec2;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::reward::Judged;
use super::settings::WalkerSettings;
use super::state::{memory_scan, Surroundings, Walker};
use crate::body::joint;
use crate::math::random::normal_samples;
use crate::motion::cvae::{BodyContext, DecodedPrimitive};
use crate::scene::{guide_aim_remembered, plan_path, Obstacle2, SeenMap};
use crate::sensing::Sensor;

/// How far along the planned path the path follower aims a primitive (m; a walking
/// primitive covers 0.2–0.7 m).
pub(crate) const PATH_LOOKAHEAD_M: f64 = 0.8;

/// Free space the planned path keeps from walls and other people (m, about half a body's
/// width).
pub(crate) const PATH_CLEARANCE_M: f64 = 0.3;

/// What a penetrating primitive costs the path follower, as extra distance (m).
pub(crate) const PATH_PENETRATION_COST_M: f64 = 1.0;

/// Which controller steers a walker and with what knobs: what configs name (`steering`, `k`,
/// `action_spread`) and reports record (`{"kind": "sampling", "k": 16}`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum ControllerSpec {
    /// The trained policy: an action sampled from π, its standard deviation scaled by
    /// `spread` (1: as trained; smaller draws nearer the mean), or its mean.
    Policy {
        mean_action: bool,
        #[serde(skip_serializing_if = "is_one")]
        spread: f32,
    },
    /// The best of `k` random latents by the environment's reward (one primitive ahead).
    Sampling { k: usize },
    /// The path-planning baseline (in the spirit of GAMMA's and DIMOS's A* paths): an A* path
    /// on the walkable map around the others' boxes as the walker sees them and the moving
    /// obstacles where they stand, replanned every primitive; of `k` random latents the one
    /// whose primitive ends nearest the path's point [`PATH_LOOKAHEAD_M`] ahead (a primitive
    /// that penetrates, Eq. 7, counts [`PATH_PENETRATION_COST_M`] farther). No policy, no
    /// reward.
    PathFollow { k: usize },
}

fn is_one(x: &f32) -> bool {
    *x == 1.0
}

impl ControllerSpec {
    /// The trained policy's sampled actions, as trained.
    pub const POLICY: ControllerSpec = ControllerSpec::Policy {
        mean_action: false,
        spread: 1.0,
    };
    /// The trained policy's mean action.
    pub(crate) const POLICY_MEAN: ControllerSpec = ControllerSpec::Policy {
        mean_action: true,
        spread: 1.0,
    };

    /// The controller's name in reports and on command lines: `policy`, `policy_mean`,
    /// `policy_spread_S`, `sampling_kK`, `path_follow_kK`.
    pub(crate) fn name(&self) -> String {
        match *self {
            ControllerSpec::Policy {
                mean_action: true, ..
            } => "policy_mean".into(),
            ControllerSpec::Policy { spread: 1.0, .. } => "policy".into(),
            ControllerSpec::Policy { spread, .. } => format!("policy_spread_{spread}"),
            ControllerSpec::Sampling { k } => format!("sampling_k{k}"),
            ControllerSpec::PathFollow { k } => format!("path_follow_k{k}"),
        }
    }

    /// The controller a name ([`Self::name`]'s) says, if any.
    pub(crate) fn from_name(name: &str) -> Option<ControllerSpec> {
        let k = |s: &str| s.parse::<usize>().ok().filter(|&k| k >= 1);
        match name {
            "policy" => Some(ControllerSpec::POLICY),
            "policy_mean" => Some(ControllerSpec::POLICY_MEAN),
            _ => {
                if let Some(s) = name.strip_prefix("policy_spread_") {
                    let spread: f32 = s
                        .parse()
                        .ok()
                        .filter(|x: &f32| x.is_finite() && *x >= 0.0)?;
                    Some(ControllerSpec::Policy {
                        mean_action: false,
                        spread,
                    })
                } else if let Some(s) = name.strip_prefix("sampling_k") {
                    Some(ControllerSpec::Sampling { k: k(s)? })
                } else {
                    Some(ControllerSpec::PathFollow {
                        k: k(name.strip_prefix("path_follow_k")?)?,
                    })
                }
            }
        }
    }

    /// Whether this controller acts through a trained policy.
    pub(crate) fn needs_policy(&self) -> bool {
        matches!(self, ControllerSpec::Policy { .. })
    }

    /// Its kind as reports name it (`"policy"`, `"sampling"`, `"path_follow"`) and the
    /// latents it proposes per primitive (`k`; a policy's one action).
    pub(crate) fn kind_and_k(&self) -> (&'static str, usize) {
        match *self {
            ControllerSpec::Policy { .. } => ("policy", 1),
            ControllerSpec::Sampling { k } => ("sampling", k),
            ControllerSpec::PathFollow { k } => ("path_follow", k),
        }
    }

    /// The controller one walker steps with: `None` when it needs a policy and none is given.
    pub(crate) fn build<'a>(
        &self,
        policy: Option<&'a dyn Policy>,
    ) -> Option<Box<dyn Controller + 'a>> {
        Some(match *self {
            ControllerSpec::Policy {
                mean_action,
                spread,
            } => Box::new(PolicyController {
                policy: policy?,
                mean_action,
                spread,
                seen: None,
            }),
            ControllerSpec::Sampling { k } => Box::new(SamplingController { k }),
            ControllerSpec::PathFollow { k } => Box::new(PathFollowController { k, aim: None }),
        })
    }
}

/// Which controller steers, as configs name it (`steering = "sampling"`); with the knobs given
/// beside it (`k`, `action_spread`) it makes a [`ControllerSpec`] ([`Self::spec`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Steering {
    /// The trained policy, actions sampled from π.
    #[default]
    Policy,
    /// The trained policy's mean action.
    PolicyMean,
    /// The best of `k` random latents by the reward.
    Sampling,
    /// The path-planning baseline.
    PathFollow,
}

impl Steering {
    /// The controller this steering makes with the knobs given beside it: `k` candidates for
    /// `sampling` and `path_follow` (default 16), `spread` of `policy`'s sampled actions
    /// (default 1); a knob given to a steering that has none is refused, by name.
    pub(crate) fn spec(
        self,
        k: Option<usize>,
        spread: Option<f32>,
    ) -> Result<ControllerSpec, String> {
        if let Some(x) = spread {
            if !(x.is_finite() && x >= 0.0) {
                return Err(format!("`action_spread`: expected a scale ≥ 0, got {x}"));
            }
            if self != Steering::Policy {
                return Err("`action_spread` is for steering = \"policy\" only".into());
            }
        }
        let k = match (self, k) {
            (Steering::Policy | Steering::PolicyMean, Some(_)) => {
                return Err("`k` is for steering = \"sampling\" or \"path_follow\" only".into())
            }
            (_, Some(0)) => return Err("`k` must be at least 1".into()),
            (_, k) => k.unwrap_or(16),
        };
        Ok(match self {
            Steering::Policy => ControllerSpec::Policy {
                mean_action: false,
                spread: spread.unwrap_or(1.0),
            },
            Steering::PolicyMean => ControllerSpec::POLICY_MEAN,
            Steering::Sampling => ControllerSpec::Sampling { k },
            Steering::PathFollow => ControllerSpec::PathFollow { k },
        })
    }
}

/// A trained policy as acting sees it: an observation in, the action distribution (mean,
/// standard deviation) out. `policy::Actor` is the shipped one.
pub trait Policy {
    /// Length of the observation it reads.
    fn obs_dim(&self) -> usize;
    /// The action distribution for one observation.
    fn distribution(&self, obs: &[f32]) -> (Vec<f32>, Vec<f32>);
}

/// What a walker knows when its controller proposes: its own state and body, what it senses,
/// the world around it, its goal and clock, and how it steps.
pub(crate) struct Sight<'a> {
    pub walker: &'a Walker,
    pub body: &'a BodyContext<'a>,
    pub sensor: &'a Sensor,
    /// The world as the walker senses it (the others where [`WalkerSettings::anticipate_people`]
    /// says).
    pub around: &'a Surroundings<'a>,
    /// The world's obstacles that do not move, which guides and paths plan round.
    pub standing: &'a [Obstacle2],
    pub goal: DVec2,
    /// The take's (or episode's) clock at the primitive's first seed frame.
    pub t0_s: f64,
    /// The share of the goal's primitives left (the observation's last value).
    pub time_left: f64,
    pub settings: &'a WalkerSettings,
    pub latent_dim: usize,
}

/// What a controller proposes for one step: latents in order, and the policy's action
/// distribution behind them where a policy drew them (redraws draw from it too).
pub(crate) struct Proposed {
    pub latents: Vec<Vec<f32>>,
    pub policy: Option<(Vec<f32>, Vec<f32>)>,
}

/// What proposes a walker's next primitive and how its proposals rank. One per walker (it may
/// keep what the walker has seen between steps).
pub(crate) trait Controller {
    /// The latents to decode for this step, drawn from `rng`.
    fn propose(&mut self, sight: &Sight, rng: &mut ChaCha8Rng) -> Proposed;
    /// A proposal's score (higher is better) once decoded and judged: by default its reward.
    fn score(&self, _primitive: &DecodedPrimitive, _judged: &Judged, reward: f64) -> f64 {
        reward
    }
}

/// [`ControllerSpec::Policy`]: one action of the policy from the walker's observation, on its
/// guide's aim where a wall hides the goal.
struct PolicyController<'a> {
    policy: &'a dyn Policy,
    mean_action: bool,
    spread: f32,
    /// What the walker's rays have shown it, where its guide plans on that
    /// ([`WalkerSettings::guide_memory`]).
    seen: Option<SeenMap>,
}

impl Controller for PolicyController<'_> {
    fn propose(&mut self, sight: &Sight, rng: &mut ChaCha8Rng) -> Proposed {
        let mut obs = vec![0f32; self.policy.obs_dim()];
        let around = sight.around;
        let memory = sight.settings.remembers().then(|| {
            let seen = self.seen.get_or_insert_with(|| SeenMap::unseen(around.map));
            sight
                .walker
                .look(&memory_scan(sight.sensor), around.map, sight.standing, seen);
            &*seen
        });
        let aim = guide_aim_remembered(
            memory,
            around.map,
            sight.standing,
            sight.walker.view.pelvis,
            sight.goal,
            &sight.settings.guide(),
        );
        sight.walker.observe_into(
            sight.body,
            sight.sensor,
            aim,
            around,
            sight.t0_s,
            sight.time_left,
            &mut obs,
        );
        let (mean, mut std) = self.policy.distribution(&obs);
        if self.spread != 1.0 {
            std.iter_mut().for_each(|s| *s *= self.spread);
        }
        let a = if self.mean_action {
            mean.clone()
        } else {
            draw_action(&mean, &std, rng)
        };
        Proposed {
            latents: vec![a],
            policy: Some((mean, std)),
        }
    }
}

/// An action `mean + std · ε`, ε ~ N(0, I) drawn from `rng`.
pub(crate) fn draw_action(mean: &[f32], std: &[f32], rng: &mut ChaCha8Rng) -> Vec<f32> {
    normal_samples(rng, mean.len())
        .iter()
        .zip(mean.iter().zip(std))
        .map(|(e, (m, s))| m + s * e)
        .collect()
}

/// The generator walker `i` of a take seeded `seed` draws from (its seed pose first, then
/// its controller's proposals and redraws).
pub(crate) fn walker_rng(seed: u64, i: usize) -> ChaCha8Rng {
    use rand_core::SeedableRng;
    ChaCha8Rng::seed_from_u64(
        seed.rotate_left(17) ^ (i as u64 + 1).wrapping_mul(0xD1B5_4A32_D192_ED03),
    )
}

/// `k` latents from N(0, I).
fn random_latents(k: usize, l: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<f32>> {
    normal_samples(rng, k.max(1) * l)
        .chunks(l)
        .map(<[f32]>::to_vec)
        .collect()
}

/// [`ControllerSpec::Sampling`]: the best of `k` random latents by the reward.
struct SamplingController {
    k: usize,
}

impl Controller for SamplingController {
    fn propose(&mut self, sight: &Sight, rng: &mut ChaCha8Rng) -> Proposed {
        Proposed {
            latents: random_latents(self.k, sight.latent_dim, rng),
            policy: None,
        }
    }
}

/// [`ControllerSpec::PathFollow`]: of `k` random latents, the one ending nearest a point
/// ahead on an A* path planned now.
struct PathFollowController {
    k: usize,
    /// This step's aim on the path.
    aim: Option<DVec2>,
}

impl Controller for PathFollowController {
    fn propose(&mut self, sight: &Sight, rng: &mut ChaCha8Rng) -> Proposed {
        let latents = random_latents(self.k, sight.latent_dim, rng);
        let obstacles: Vec<Obstacle2> = sight
            .around
            .moving
            .iter()
            .map(|m| m.at(sight.t0_s))
            .chain(sight.around.obstacle.copied())
            .collect();
        let path = plan_path(
            sight.around.map,
            &obstacles,
            PATH_CLEARANCE_M,
            sight.walker.view.pelvis,
            sight.goal,
        );
        self.aim = Some(path.point_along(PATH_LOOKAHEAD_M));
        Proposed {
            latents,
            policy: None,
        }
    }

    fn score(&self, p: &DecodedPrimitive, j: &Judged, reward: f64) -> f64 {
        let Some(aim) = self.aim else {
            return reward;
        };
        let end = p.joints[p.joints.len() - 1][joint::PELVIS];
        let miss = DVec2::new(end.x, end.y).distance(aim);
        -(miss
            + if j.penetrated {
                PATH_PENETRATION_COST_M
            } else {
                0.0
            })
    }
}

#[cfg(test)]
mod tests {
    use super::ControllerSpec;

    #[test]
    fn a_controllers_name_says_it_back() {
        for spec in [
            ControllerSpec::POLICY,
            ControllerSpec::POLICY_MEAN,
            ControllerSpec::Policy {
                mean_action: false,
                spread: 0.5,
            },
            ControllerSpec::Sampling { k: 16 },
            ControllerSpec::PathFollow { k: 1 },
        ] {
            assert_eq!(
                ControllerSpec::from_name(&spec.name()),
                Some(spec),
                "{spec:?}"
            );
        }
        for bad in [
            "sampling_k0",
            "sampling_k",
            "path_follow_kx",
            "policy_spread_-1",
            "walk",
        ] {
            assert_eq!(ControllerSpec::from_name(bad), None, "{bad}");
        }
    }
}
