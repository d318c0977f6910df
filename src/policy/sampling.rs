//! The sampling controller: the no-training baseline beside the policy. For every episode,
//! `k` latents drawn from N(0, I) are decoded and judged by the environment's own reward
//! (one primitive of lookahead) and the best is taken. `k` is the speed/accuracy knob: one
//! step costs `k` decodes per episode; `k = 1` is the plain random walk. [`best_of`] is the
//! one rule by which every controller chooses among judged primitives.

use rand_chacha::ChaCha8Rng;

use super::env::{Candidate, EnvError, PolicyEnv, StepOutput};
use crate::motion::cvae::train::normal_samples;

/// One step of every episode with the best of `k` random latents.
pub fn sampling_step(
    env: &mut PolicyEnv,
    k: usize,
    rng: &mut ChaCha8Rng,
) -> Result<StepOutput, EnvError> {
    let k = k.max(1);
    let latents = normal_samples(rng, env.len() * k * env.latent_dim());
    let mut per_episode: Vec<Vec<Candidate>> = (0..env.len()).map(|_| Vec::new()).collect();
    for c in env.propose(&latents, k)? {
        per_episode[c.env].push(c);
    }
    env.commit(
        per_episode
            .into_iter()
            .map(|candidates| {
                best_of(candidates.into_iter().map(|c| {
                    let score = c.primitive.is_some().then_some(c.reward);
                    (c, score)
                }))
                .expect("k ≥ 1 candidates per episode")
            })
            .collect(),
    )
}

/// How every controller chooses among judged primitives (the sampling controller here, the
/// crowd's agents in `synth`): the one of highest score; a candidate that did not decode
/// (`None`) never beats one that did, a non-finite score counts as −∞, and among equals the
/// first is kept. `None` only when there is no candidate.
pub fn best_of<T>(candidates: impl IntoIterator<Item = (T, Option<f64>)>) -> Option<T> {
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
