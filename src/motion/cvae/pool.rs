//! Seeds that random-latent chains start from in prior fine-tuning: fresh mocap seeds and the
//! ends of earlier random chains, so that training sees the states long chains reach.
//!
//! Two kinds of pool. `Recent` keeps the last chain ends and continues uniformly drawn ones:
//! a chain rarely continues one that itself continued another, so training sees states a few
//! chains deep. `Slots` is a fixed set of persistent chains (the sample pool of neural
//! cellular automata): each step continues some of them and writes their ends back, so a slot's
//! chain grows step after step — hundreds of primitives deep — until it leaves the human range
//! or is reset to a mocap seed.

use std::collections::VecDeque;

use rand_chacha::ChaCha8Rng;
use rand_core::Rng;

use super::data::PrimitiveSet;
use super::features::FRAME_DIM;
use crate::motion::primitive::SEED_FRAMES;

/// Values of one seed.
const SEED_VALUES: usize = SEED_FRAMES * FRAME_DIM;

/// Chain ends the `Recent` pool keeps (oldest dropped first).
pub(crate) const RECENT_CAPACITY: usize = 4096;

/// A seed (`[S × F]` raw features), its canonical floor (m) and how many random primitives
/// separate it from the mocap seed its chain started from.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct PoolSeed {
    pub frames: Vec<f32>,
    pub floor: f32,
    pub depth: usize,
}

/// Seeds of the random chains (see the module docs).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) enum SeedPool {
    Recent(VecDeque<PoolSeed>),
    /// `None`: the slot starts from a fresh mocap seed when next drawn.
    Slots(Vec<Option<PoolSeed>>),
}

/// The seeds of one batch of random chains, and where their ends go back.
#[derive(Debug, Clone)]
pub(crate) struct Draw {
    /// `[B × S × F]`.
    pub seeds: Vec<f32>,
    /// `[B]`.
    pub floors: Vec<f32>,
    pub depths: Vec<usize>,
    /// The slot of each chain (`Slots` only).
    slots: Vec<Option<usize>>,
}

/// A uniform draw in [0, 1) from 53 random bits.
fn unit(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

impl SeedPool {
    /// A `Recent` pool (`slots` = None) or `slots` persistent chains.
    pub(crate) fn new(slots: Option<usize>) -> Self {
        match slots {
            None => Self::Recent(VecDeque::new()),
            Some(n) => Self::Slots(vec![None; n]),
        }
    }

    /// Seeds of `size` random chains: each continues a pooled chain with probability
    /// `continue_share`, else starts from the first seed of a random item of `set`.
    pub(crate) fn draw(
        &self,
        set: &PrimitiveSet,
        continue_share: f64,
        size: usize,
        rng: &mut ChaCha8Rng,
    ) -> Draw {
        let mut draw = Draw {
            seeds: Vec::with_capacity(size * SEED_VALUES),
            floors: Vec::with_capacity(size),
            depths: Vec::with_capacity(size),
            slots: Vec::with_capacity(size),
        };
        let fresh = |draw: &mut Draw, rng: &mut ChaCha8Rng| {
            let i = (rng.next_u64() % set.len() as u64) as usize;
            draw.seeds.extend_from_slice(&set.item(i)[..SEED_VALUES]);
            draw.floors.push(set.floors(i)[0]);
            draw.depths.push(0);
        };
        match self {
            Self::Recent(ends) => {
                for _ in 0..size {
                    let pooled = !ends.is_empty() && unit(rng) < continue_share;
                    if pooled {
                        let e = &ends[(rng.next_u64() % ends.len() as u64) as usize];
                        draw.push(e);
                    } else {
                        fresh(&mut draw, rng);
                    }
                    draw.slots.push(None);
                }
            }
            Self::Slots(slots) => {
                // `size` distinct slots (a partial Fisher-Yates shuffle).
                let mut order: Vec<usize> = (0..slots.len()).collect();
                for k in 0..size.min(slots.len()) {
                    let j = k + (rng.next_u64() % (slots.len() - k) as u64) as usize;
                    order.swap(k, j);
                    let slot = order[k];
                    match &slots[slot] {
                        Some(e) if unit(rng) < continue_share => draw.push(e),
                        _ => fresh(&mut draw, rng),
                    }
                    draw.slots.push(Some(slot));
                }
            }
        }
        draw
    }

    /// Takes the ends of the chains of `draw`, `primitives` long: `ends` `[B × S × F]`,
    /// `floors` `[B]`; `keep[i]` false drops chain `i`'s end (a `Slots` slot then restarts
    /// from mocap). Non-finite ends are always dropped.
    pub(crate) fn accept(
        &mut self,
        draw: &Draw,
        ends: &[f32],
        floors: &[f32],
        keep: &[bool],
        primitives: usize,
    ) {
        for (i, &floor) in floors.iter().enumerate() {
            let frames = &ends[i * SEED_VALUES..(i + 1) * SEED_VALUES];
            let finite = floor.is_finite() && frames.iter().all(|v| v.is_finite());
            let end = (finite && keep[i]).then(|| PoolSeed {
                frames: frames.to_vec(),
                floor,
                depth: draw.depths[i] + primitives,
            });
            match self {
                Self::Recent(pool) => {
                    if let Some(end) = end {
                        if pool.len() == RECENT_CAPACITY {
                            pool.pop_front();
                        }
                        pool.push_back(end);
                    }
                }
                Self::Slots(slots) => {
                    if let Some(slot) = draw.slots[i] {
                        slots[slot] = end;
                    }
                }
            }
        }
    }

    /// A uniformly drawn pooled seed, if any.
    pub(crate) fn sample(&self, rng: &mut ChaCha8Rng) -> Option<&PoolSeed> {
        match self {
            Self::Recent(ends) => match ends.len() {
                0 => None,
                n => Some(&ends[(rng.next_u64() % n as u64) as usize]),
            },
            Self::Slots(slots) => {
                let filled: Vec<&PoolSeed> = slots.iter().flatten().collect();
                match filled.len() {
                    0 => None,
                    n => Some(filled[(rng.next_u64() % n as u64) as usize]),
                }
            }
        }
    }
}

impl Draw {
    fn push(&mut self, e: &PoolSeed) {
        self.seeds.extend_from_slice(&e.frames);
        self.floors.push(e.floor);
        self.depths.push(e.depth);
    }

    /// Chains in the batch.
    pub(crate) fn len(&self) -> usize {
        self.floors.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;

    fn set(items: usize) -> PrimitiveSet {
        let mut s = PrimitiveSet::new(1);
        for i in 0..items {
            s.features.extend(std::iter::repeat_n(
                i as f32,
                crate::motion::primitive::PRIMITIVE_FRAMES * FRAME_DIM,
            ));
            s.floor_z.push(-(i as f32));
        }
        s
    }

    #[test]
    fn slots_grow_deep_chains_and_restart_dropped_ones() {
        let set = set(5);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut pool = SeedPool::new(Some(4));
        for step in 0..20 {
            let draw = pool.draw(&set, 1.0, 4, &mut rng);
            assert_eq!(draw.len(), 4);
            // Every slot is drawn each step and continued: depth = 3 primitives per step.
            assert!(
                draw.depths.iter().all(|&d| d == 3 * step),
                "{:?}",
                draw.depths
            );
            let ends = vec![0.5; 4 * SEED_VALUES];
            pool.accept(&draw, &ends, &[0.0; 4], &[true; 4], 3);
        }
        // Dropped ends restart from mocap (depth 0, mocap floors).
        let draw = pool.draw(&set, 1.0, 4, &mut rng);
        pool.accept(
            &draw,
            &[f32::NAN; 4 * SEED_VALUES],
            &[0.0; 4],
            &[true; 4],
            3,
        );
        let draw = pool.draw(&set, 1.0, 4, &mut rng);
        assert!(draw.depths.iter().all(|&d| d == 0));
        assert!(draw.floors.iter().all(|&f| f <= 0.0 && f == f.round()));
        let kept = [true, false, true, false];
        pool.accept(&draw, &vec![0.5; 4 * SEED_VALUES], &[0.0; 4], &kept, 2);
        let mut depths = pool.draw(&set, 1.0, 4, &mut rng).depths;
        depths.sort();
        assert_eq!(depths, vec![0, 0, 2, 2]);
    }

    #[test]
    fn recent_pool_continues_ends_at_the_given_share() {
        let set = set(3);
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let mut pool = SeedPool::new(None);
        // Empty: all chains start from mocap.
        let draw = pool.draw(&set, 1.0, 8, &mut rng);
        assert!(draw.depths.iter().all(|&d| d == 0));
        pool.accept(
            &draw,
            &vec![0.25; 8 * SEED_VALUES],
            &[0.0; 8],
            &[true; 8],
            4,
        );
        let draw = pool.draw(&set, 0.5, 1000, &mut rng);
        let pooled = draw.depths.iter().filter(|&&d| d == 4).count();
        assert!((400..600).contains(&pooled), "{pooled}");
        assert!(pool.sample(&mut rng).is_some());
    }
}
