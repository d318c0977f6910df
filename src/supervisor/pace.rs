//! The rendering ETA: time left from each camera's own measured seconds per frame. A take's
//! cameras cost apart by their pixel counts (the default take's Aria RGB frame about 6× a SLAM
//! frame), so averaging over all frames done misjudges what is left whenever the mix of
//! cameras rendered so far differs from the mix still to come.
//!
//! A camera's seconds per frame are the worker seconds of its shard attempts that ended over
//! the frames they finished (Blender's start-up and scene sync included). Whole attempts, not
//! frames: a shard's frames are finished in a burst at its end, so a frame's own share of the
//! attempt says nothing until the burst is over. An attempt still running counts its time so
//! far as done and its frames not yet finished as what is left of it (at least a twentieth of
//! its expected time). A camera with no attempt ended yet is priced by its pixels at the
//! measured cameras' seconds per pixel, or by the frames its running attempts finished (each
//! charged the time since the previous frame of its attempt) where those say it is cheaper;
//! before any attempt has ended, by those frames alone. The time left is
//! then the wall time so far scaled by the worker seconds left over those done, which carries
//! the pool's real concurrency (workers, queue waits, staging) without modelling it. Frames
//! not yet staged (a campaign's later takes) are priced at the mean of the staged ones.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Per-camera pace of one start's rendering; shared by a pool's workers (interior locking).
#[derive(Debug, Default)]
pub(crate) struct FramePace {
    state: Mutex<PaceState>,
}

#[derive(Debug, Default)]
struct PaceState {
    /// By camera name.
    cameras: BTreeMap<String, CameraPace>,
    /// Attempts running now.
    running: BTreeMap<u64, RunningAttempt>,
    next_key: u64,
}

#[derive(Debug)]
struct RunningAttempt {
    camera: String,
    /// Frames it was given and frames it has finished.
    frames: u64,
    finished: u64,
    began: Instant,
    /// When its last frame finished (or it began).
    last: Instant,
}

/// A running attempt's handle on its pool's [`FramePace`]; dropping it ends the attempt.
#[derive(Debug)]
pub(crate) struct PaceAttempt {
    pace: Arc<FramePace>,
    key: u64,
}

impl PaceAttempt {
    /// The attempt finished a frame now.
    pub(crate) fn frame_done(&self) {
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
    /// Frames done this start, and the worker seconds charged to them one by one.
    done: u64,
    seconds: f64,
    /// Frames finished by attempts that ended, and those attempts' worker seconds.
    ended_frames: u64,
    ended_seconds: f64,
}

impl FramePace {
    /// `frames` more frames of `camera` (`pixels` a frame) to render.
    pub(crate) fn plan(&self, camera: &str, pixels: u64, frames: u64) {
        let mut s = self.state.lock().unwrap();
        let c = s.cameras.entry(camera.to_owned()).or_default();
        c.pixels = pixels.max(1);
        c.left += frames;
    }

    /// An attempt at `frames` frames of `camera` starts now; it ends when the returned handle
    /// is dropped.
    pub(crate) fn attempt(self: &Arc<Self>, camera: &str, frames: u64) -> PaceAttempt {
        let key = {
            let mut s = self.state.lock().unwrap();
            s.next_key += 1;
            s.next_key
        };
        self.begin_at(key, camera, frames, Instant::now());
        PaceAttempt {
            pace: self.clone(),
            key,
        }
    }

    fn end(&self, key: u64) {
        self.end_at(key, Instant::now());
    }

    /// The attempt's worker seconds and finished frames join its camera's ended ones (an
    /// attempt that failed included: its time was spent on this camera's frames).
    fn end_at(&self, key: u64, now: Instant) {
        let mut s = self.state.lock().unwrap();
        let Some(a) = s.running.remove(&key) else {
            return;
        };
        let c = s.cameras.entry(a.camera).or_default();
        c.ended_frames += a.finished;
        c.ended_seconds += now.saturating_duration_since(a.began).as_secs_f64();
    }

    /// Time left after `elapsed` of wall time with `to_go` frames still to render (those not
    /// planned yet among them); `None` until a frame is done.
    pub(crate) fn time_left(&self, elapsed: Duration, to_go: u64) -> Option<Duration> {
        self.time_left_at(elapsed, to_go, Instant::now())
    }

    fn begin_at(&self, key: u64, camera: &str, frames: u64, now: Instant) {
        let mut s = self.state.lock().unwrap();
        let attempt = RunningAttempt {
            camera: camera.to_owned(),
            frames,
            finished: 0,
            began: now,
            last: now,
        };
        s.running.insert(key, attempt);
    }

    fn frame_done_at(&self, key: u64, now: Instant) {
        let mut s = self.state.lock().unwrap();
        let Some(a) = s.running.get_mut(&key) else {
            return;
        };
        let seconds = now.saturating_duration_since(a.last).as_secs_f64();
        a.last = now;
        a.finished += 1;
        let camera = a.camera.clone();
        let c = s.cameras.entry(camera).or_default();
        c.left = c.left.saturating_sub(1);
        c.done += 1;
        c.seconds += seconds;
    }

    fn time_left_at(&self, elapsed: Duration, to_go: u64, now: Instant) -> Option<Duration> {
        let s = self.state.lock().unwrap();
        let (seconds, left, done_frames) = if s.cameras.values().any(|c| c.ended_frames > 0) {
            by_attempts(&s, now)
        } else {
            by_frames(&s, now)?
        };
        let planned: u64 = s.cameras.values().map(|c| c.left).sum();
        let unstaged = to_go.saturating_sub(planned);
        let mut left = left;
        if unstaged > 0 {
            let mean = if planned > 0 {
                left / planned as f64
            } else {
                seconds / done_frames.max(1) as f64
            };
            left += mean * unstaged as f64;
        }
        Some(Duration::from_secs_f64(
            elapsed.as_secs_f64() * left / seconds.max(1e-9),
        ))
    }
}

/// (worker seconds done, worker seconds left, frames done) from the attempts that ended, the
/// running ones counting their time so far and the rest of their expected time.
fn by_attempts(s: &PaceState, now: Instant) -> (f64, f64, u64) {
    let (mut seconds, pixels, frames) = s.cameras.values().fold((0.0, 0.0, 0), |(t, p, n), c| {
        (
            t + c.ended_seconds,
            p + (c.ended_frames * c.pixels) as f64,
            n + c.ended_frames,
        )
    });
    let per_pixel = seconds / pixels.max(1.0);
    // A camera whose first attempt is still running: by its frames finished so far where
    // they say it is cheaper than its pixels do (the first frame of a burst is charged its
    // whole attempt: that says nothing yet).
    let per_frame = |c: &CameraPace| match (c.ended_frames, c.done) {
        (0, 0) => per_pixel * c.pixels as f64,
        (0, n) => (c.seconds / n as f64).min(per_pixel * c.pixels as f64),
        (n, _) => c.ended_seconds / n as f64,
    };
    let mut left: f64 = s
        .cameras
        .values()
        .map(|c| c.left as f64 * per_frame(c))
        .sum();
    for a in s.running.values() {
        let pace = s.cameras.get(&a.camera).map_or(0.0, per_frame);
        let spent = now.saturating_duration_since(a.began).as_secs_f64();
        let expected = a.frames as f64 * pace;
        // Its frames not yet finished are in its camera's `left`: they are priced here.
        left -= a.frames.saturating_sub(a.finished) as f64 * pace;
        left += (expected - spent).max(expected / 20.0);
        seconds += spent;
    }
    (seconds, left.max(0.0), frames)
}

/// (worker seconds done, worker seconds left, frames done) from the frames finished, each
/// charged the time since the previous frame of its attempt; `None` until a frame is done.
fn by_frames(s: &PaceState, now: Instant) -> Option<(f64, f64, u64)> {
    let measured = || s.cameras.values().filter(|c| c.done > 0);
    let (seconds, pixels, frames): (f64, f64, u64) = measured()
        .fold((0.0, 0.0, 0), |(t, p, n), c| {
            (t + c.seconds, p + (c.done * c.pixels) as f64, n + c.done)
        });
    if pixels == 0.0 {
        return None;
    }
    let per_pixel = seconds / pixels;
    let left: f64 = s
        .cameras
        .values()
        .map(|c| match c.done {
            0 => c.left as f64 * per_pixel * c.pixels as f64,
            n => c.left as f64 * c.seconds / n as f64,
        })
        .sum();
    // Work in progress counts as done, and as no longer left.
    let running: f64 = s
        .running
        .values()
        .map(|a| now.saturating_duration_since(a.last).as_secs_f64())
        .sum();
    Some((seconds + running, (left - running).max(0.0), frames))
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
        pace.begin_at(1, "slam", 10, t0);
        for k in 1..=10 {
            pace.frame_done_at(1, t0 + s(k as f64));
        }
        pace.end_at(1, t0 + s(10.0));
        // 10 RGB frames priced by pixels: 6 s each, one worker: 60 s.
        let eta = pace.time_left_at(s(10.0), 10, t0 + s(10.0)).unwrap();
        assert!((eta.as_secs_f64() - 60.0).abs() < 1e-6, "{eta:?}");
        // RGB measured at 3 s a frame: 5 done, 5 left, 15 s.
        pace.begin_at(2, "rgb", 10, t0 + s(10.0));
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
        pace.begin_at(1, "a", 10, t0);
        pace.begin_at(2, "a", 10, t0);
        for k in 1..=5 {
            pace.frame_done_at(1, t0 + s(2.0 * k as f64));
            pace.frame_done_at(2, t0 + s(2.0 * k as f64));
        }
        // 10 done in 10 s at 2 s of worker time each; 10 left: 20 worker seconds, 10 s.
        let eta = pace.time_left_at(s(10.0), 10, t0 + s(10.0)).unwrap();
        assert!((eta.as_secs_f64() - 10.0).abs() < 1e-6, "{eta:?}");
        // The first attempt ends (its 5 frames in 10 s): the same pace by attempts; a frame
        // of an attempt not begun (or ended) is not charged.
        pace.end_at(1, t0 + s(10.0));
        pace.frame_done_at(1, t0 + s(11.0));
        let eta2 = pace.time_left_at(s(10.0), 10, t0 + s(10.0)).unwrap();
        assert!((eta2.as_secs_f64() - 10.0).abs() < 1e-6, "{eta2:?}");
    }

    /// A shard's frames finished in a burst at its end: once an attempt has ended, the next
    /// one's first frame of its burst (charged the whole attempt) does not make the camera
    /// look slower; the ETA is what is left of the running attempt at the first one's pace.
    #[test]
    fn a_burst_of_frames_is_priced_by_whole_attempts() {
        let pace = FramePace::default();
        pace.plan("a", 100, 50);
        let t0 = Instant::now();
        pace.begin_at(1, "a", 25, t0);
        for k in 0..25 {
            pace.frame_done_at(1, t0 + s(24.0 + k as f64 / 25.0));
        }
        pace.end_at(1, t0 + s(25.0));
        pace.begin_at(2, "a", 25, t0 + s(25.0));
        // Halfway through the second: half of its 25 s left.
        let eta = pace.time_left_at(s(37.5), 25, t0 + s(37.5)).unwrap();
        assert!((eta.as_secs_f64() - 12.5).abs() < 1e-6, "{eta:?}");
        // Its burst begins: one frame finished after 24 s, the rest will follow within 1 s.
        pace.frame_done_at(2, t0 + s(49.0));
        let eta = pace.time_left_at(s(49.0), 24, t0 + s(49.0)).unwrap();
        assert!((eta.as_secs_f64() - 1.25).abs() < 1e-6, "{eta:?}");
        // Overrunning its expected time, it is still given a twentieth of it.
        let eta = pace.time_left_at(s(60.0), 24, t0 + s(60.0)).unwrap();
        assert!((eta.as_secs_f64() - 1.25).abs() < 1e-6, "{eta:?}");
    }

    /// 10 SLAM frames (100 px) done in one attempt of 10 s that ended; an attempt at 10 of 20
    /// RGB frames (600 px) begun at 10 s (key 2).
    fn slam_ended_rgb_begun(t0: Instant) -> FramePace {
        let pace = FramePace::default();
        pace.plan("slam", 100, 10);
        pace.plan("rgb", 600, 20);
        pace.begin_at(1, "slam", 10, t0);
        for k in 1..=10 {
            pace.frame_done_at(1, t0 + s(k as f64));
        }
        pace.end_at(1, t0 + s(10.0));
        pace.begin_at(2, "rgb", 10, t0 + s(10.0));
        pace
    }

    /// A camera's first attempt finishing its frames in a burst while another camera has
    /// ended attempts: the burst's first frame (charged the whole attempt) does not make it
    /// look dearer than its pixels say; frames finished one by one that say it is cheaper do.
    #[test]
    fn a_first_burst_is_priced_by_pixels_until_its_attempt_ends() {
        let t0 = Instant::now();
        // SLAM: 10 frames in 10 s, ended. RGB: priced by pixels at 6 s a frame.
        let pace = slam_ended_rgb_begun(t0);
        // 40 s into the RGB attempt, the first frame of its burst: still 6 s a frame, so its
        // attempt has 20 s left and the other 10 frames 60 s: 80 worker seconds of 50 done.
        pace.frame_done_at(2, t0 + s(50.0));
        let eta = pace.time_left_at(s(50.0), 19, t0 + s(50.0)).unwrap();
        assert!((eta.as_secs_f64() - 80.0).abs() < 1e-6, "{eta:?}");
        // Frames one by one at 2 s each say it is cheaper than its pixels: 2 s a frame.
        let pace = slam_ended_rgb_begun(t0);
        for k in 1..=5 {
            pace.frame_done_at(2, t0 + s(10.0 + 2.0 * k as f64));
        }
        // Its attempt: 20 s expected, 10 spent, 10 left; the next 10 frames 20 s: 30 of 20 done.
        let eta = pace.time_left_at(s(20.0), 15, t0 + s(20.0)).unwrap();
        assert!((eta.as_secs_f64() - 30.0).abs() < 1e-6, "{eta:?}");
    }
}
