//! The rendering ETA: time left from each camera's own measured seconds per frame. A take's
//! cameras cost apart by their pixel counts (the default take's Aria RGB frame about 6× a SLAM
//! frame), so averaging over all frames done misjudges what is left whenever the mix of
//! cameras rendered so far differs from the mix still to come.
//!
//! Each frame is charged the worker time since the previous frame of its shard attempt
//! finished (the first frame of an attempt: since the attempt started, Blender's start-up
//! and scene sync included). A camera's seconds per frame are its charged seconds over its
//! frames; a camera with no frame done yet is priced by its pixels at the measured cameras'
//! seconds per pixel. The time left is then the wall time so far scaled by the worker seconds
//! left over those done, which carries the pool's real concurrency (workers, queue waits,
//! staging) without modelling it. Frames not yet staged (a campaign's later takes) are priced
//! at the mean of the staged ones.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Per-camera pace of one start's rendering; shared by a pool's workers (interior locking).
#[derive(Debug, Default)]
pub struct FramePace {
    state: Mutex<PaceState>,
}

#[derive(Debug, Default)]
struct PaceState {
    /// By camera name.
    cameras: BTreeMap<String, CameraPace>,
    /// Attempts running now: camera name and when their last frame finished (or they began).
    running: BTreeMap<u64, (String, Instant)>,
    next_key: u64,
}

/// A running attempt's handle on its pool's [`FramePace`]; dropping it ends the attempt.
#[derive(Debug)]
pub struct PaceAttempt {
    pace: Arc<FramePace>,
    key: u64,
}

impl PaceAttempt {
    /// The attempt finished a frame now.
    pub fn frame_done(&self) {
        self.pace.frame_done_at(self.key, Instant::now());
    }
}

impl Drop for PaceAttempt {
    fn drop(&mut self) {
        self.pace.end(self.key);
    }
}

#[derive(Debug, Default, Clone)]
struct CameraPace {
    /// Pixels of one frame (what prices a camera not yet measured).
    pixels: u64,
    /// Frames planned and not yet done.
    left: u64,
    /// Frames done this start, and the worker seconds charged to them.
    done: u64,
    seconds: f64,
}

impl FramePace {
    /// `frames` more frames of `camera` (`pixels` a frame) to render.
    pub fn plan(&self, camera: &str, pixels: u64, frames: u64) {
        let mut s = self.state.lock().unwrap();
        let c = s.cameras.entry(camera.to_owned()).or_default();
        c.pixels = pixels.max(1);
        c.left += frames;
    }

    /// An attempt at a shard of `camera` starts now; it ends when the returned handle is
    /// dropped (its time since its last frame is then charged to no frame).
    pub fn attempt(self: &Arc<Self>, camera: &str) -> PaceAttempt {
        let key = {
            let mut s = self.state.lock().unwrap();
            s.next_key += 1;
            s.next_key
        };
        self.begin_at(key, camera, Instant::now());
        PaceAttempt {
            pace: self.clone(),
            key,
        }
    }

    fn end(&self, key: u64) {
        self.state.lock().unwrap().running.remove(&key);
    }

    /// Time left after `elapsed` of wall time with `to_go` frames still to render (those not
    /// planned yet among them); `None` until a frame is done.
    pub fn time_left(&self, elapsed: Duration, to_go: u64) -> Option<Duration> {
        self.time_left_at(elapsed, to_go, Instant::now())
    }

    fn begin_at(&self, key: u64, camera: &str, now: Instant) {
        let mut s = self.state.lock().unwrap();
        s.running.insert(key, (camera.to_owned(), now));
    }

    fn frame_done_at(&self, key: u64, now: Instant) {
        let mut s = self.state.lock().unwrap();
        let Some((camera, since)) = s.running.get_mut(&key) else {
            return;
        };
        let seconds = now.saturating_duration_since(*since).as_secs_f64();
        *since = now;
        let camera = camera.clone();
        let c = s.cameras.entry(camera).or_default();
        c.left = c.left.saturating_sub(1);
        c.done += 1;
        c.seconds += seconds;
    }

    fn time_left_at(&self, elapsed: Duration, to_go: u64, now: Instant) -> Option<Duration> {
        let s = self.state.lock().unwrap();
        let measured = || s.cameras.values().filter(|c| c.done > 0);
        let (seconds, pixels): (f64, f64) = measured().fold((0.0, 0.0), |(t, p), c| {
            (t + c.seconds, p + (c.done * c.pixels) as f64)
        });
        if pixels == 0.0 {
            return None;
        }
        let per_pixel = seconds / pixels;
        let per_frame = |c: &CameraPace| match c.done {
            0 => per_pixel * c.pixels as f64,
            n => c.seconds / n as f64,
        };
        let planned: u64 = s.cameras.values().map(|c| c.left).sum();
        let unstaged = to_go.saturating_sub(planned);
        let mut left: f64 = s
            .cameras
            .values()
            .map(|c| c.left as f64 * per_frame(c))
            .sum();
        if unstaged > 0 {
            let mean = if planned > 0 {
                left / planned as f64
            } else {
                seconds / measured().map(|c| c.done).sum::<u64>() as f64
            };
            left += mean * unstaged as f64;
        }
        // Work in progress counts as done, and as no longer left.
        let running: f64 = s
            .running
            .values()
            .map(|(_, since)| now.saturating_duration_since(*since).as_secs_f64())
            .sum();
        let done = seconds + running;
        let left = (left - running).max(0.0);
        Some(Duration::from_secs_f64(
            elapsed.as_secs_f64() * left / done.max(1e-9),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(x: f64) -> Duration {
        Duration::from_secs_f64(x)
    }

    /// Two cameras 6× apart in cost, one worker: after the cheap camera's frames alone, the
    /// ETA prices the expensive one by pixels, and once it is measured by its own pace.
    #[test]
    fn each_camera_is_priced_by_its_own_pace() {
        let pace = FramePace::default();
        pace.plan("rgb", 600, 10);
        pace.plan("slam", 100, 10);
        let t0 = Instant::now();
        assert_eq!(pace.time_left_at(s(0.0), 0, t0), None);
        // SLAM frames at 1 s each.
        pace.begin_at(1, "slam", t0);
        for k in 1..=10 {
            pace.frame_done_at(1, t0 + s(k as f64));
        }
        pace.end(1);
        // 10 RGB frames priced by pixels: 6 s each, one worker: 60 s.
        let eta = pace.time_left_at(s(10.0), 10, t0 + s(10.0)).unwrap();
        assert!((eta.as_secs_f64() - 60.0).abs() < 1e-6, "{eta:?}");
        // RGB measured at 3 s a frame: 5 done, 5 left, 15 s.
        pace.begin_at(2, "rgb", t0 + s(10.0));
        for k in 1..=5 {
            pace.frame_done_at(2, t0 + s(10.0 + 3.0 * k as f64));
        }
        let eta = pace.time_left_at(s(25.0), 5, t0 + s(25.0)).unwrap();
        assert!((eta.as_secs_f64() - 15.0).abs() < 1e-6, "{eta:?}");
        // Half a frame into the next: 1.5 s of it counts as done.
        let eta = pace.time_left_at(s(26.5), 5, t0 + s(26.5)).unwrap();
        assert!((eta.as_secs_f64() - 13.5).abs() < 1e-6, "{eta:?}");
        // Frames not staged yet, at the mean of those planned (3 s): 4 more, 12 s more.
        let eta = pace.time_left_at(s(25.0), 9, t0 + s(25.0)).unwrap();
        assert!((eta.as_secs_f64() - 27.0).abs() < 1e-6, "{eta:?}");
    }

    /// Two workers side by side: the wall time scales the worker seconds, so the ETA is half
    /// the work left.
    #[test]
    fn concurrency_comes_from_the_wall_time() {
        let pace = FramePace::default();
        pace.plan("a", 1, 20);
        let t0 = Instant::now();
        pace.begin_at(1, "a", t0);
        pace.begin_at(2, "a", t0);
        for k in 1..=5 {
            pace.frame_done_at(1, t0 + s(2.0 * k as f64));
            pace.frame_done_at(2, t0 + s(2.0 * k as f64));
        }
        // 10 done in 10 s at 2 s of worker time each; 10 left: 20 worker seconds, 10 s.
        let eta = pace.time_left_at(s(10.0), 10, t0 + s(10.0)).unwrap();
        assert!((eta.as_secs_f64() - 10.0).abs() < 1e-6, "{eta:?}");
        // A frame of an attempt not begun (or ended) is not charged.
        pace.end(1);
        pace.frame_done_at(1, t0 + s(11.0));
        let eta2 = pace.time_left_at(s(10.0), 10, t0 + s(10.0)).unwrap();
        assert_eq!(eta, eta2);
    }
}
