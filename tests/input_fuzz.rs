//! Every reader of a file users bring, against damaged input: a real file of each kind (shipped
//! configs, rigs, calibrations, scenes, motion, weights, fixtures) is truncated at many points,
//! has bits flipped, header bytes overwritten, runs removed, or is replaced by random bytes;
//! text formats also have tokens changed — a number made extreme (0, −0, −1, ±1e308, 1e-320,
//! nan, ±inf, 2^63, 2^64, 40 digits), a line duplicated, deleted or swapped with another, a
//! string value emptied — so that changed files reach the readers' checks, not only their
//! parsers. The reader must answer with `Ok` or an error naming the file — never a panic, an
//! abort (which ends this test process, failing it too) or a hang: each case is read on its own
//! thread and fails past a deadline.
//!
//! CI runs a small form. `EGOGEN_FUZZ_CASES=N` sets the cases per reader (beyond the fixed
//! truncation points), `EGOGEN_FUZZ_TIMEOUT_S` the deadline per case (default 30 s, 10 s in a
//! release build), `EGOGEN_FUZZ_KEEP` the folder a failing case's files are kept in (default
//! `egogen-fuzz-failures` under the system temp folder), so that it can be read again:
//!
//! ```text
//! EGOGEN_FUZZ_CASES=2000 cargo test --release --locked --test input_fuzz -- --nocapture
//! ```
//!
//! Each reader prints a line: cases, refused, still readable, seconds.

use std::fmt::Display;
use std::path::{Path, PathBuf};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use egogen::body::BodyModel;
use egogen::inspect::ExrContents;
use egogen::motion::amass::MotionSequence;
use egogen::motion::bvh::BvhClip;
use egogen::motion::deepmimic::import_deepmimic;
use egogen::rig::Rig;
use egogen::scene::load_scene;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Cases per reader (beyond the fixed truncation points).
fn cases() -> usize {
    std::env::var("EGOGEN_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(24)
}

/// How long one case may take before it counts as a hang.
fn deadline() -> Duration {
    let default = if cfg!(debug_assertions) { 30.0 } else { 10.0 };
    let s = std::env::var("EGOGEN_FUZZ_TIMEOUT_S")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0)
        .unwrap_or(default);
    Duration::from_secs_f64(s)
}

/// Where failing cases are kept.
fn keep_dir() -> PathBuf {
    std::env::var_os("EGOGEN_FUZZ_KEEP")
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("egogen-fuzz-failures"))
}

/// A reader stops after this many hangs (each costs a whole deadline).
const MAX_HANGS: usize = 3;

/// SplitMix64: a small deterministic generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// `good` with one byte-level change of kind `kind` (0–3): flipped bits, overwritten header
/// bytes, a removed run, random bytes.
fn byte_damage(good: &[u8], rng: &mut Rng, kind: usize) -> (&'static str, Vec<u8>) {
    let n = good.len();
    let mut b = good.to_vec();
    let what = match kind % 4 {
        0 => {
            for _ in 0..1 + rng.below(8) {
                let i = rng.below(n);
                b[i] ^= 1 << rng.below(8);
            }
            "flipped bits"
        }
        1 => {
            // Header-heavy formats keep sizes and counts near the front.
            let i = rng.below(n.min(512));
            let v = rng.next().to_le_bytes();
            for (k, byte) in v.iter().enumerate() {
                if i + k < n {
                    b[i + k] = *byte;
                }
            }
            "overwritten header bytes"
        }
        2 => {
            let i = rng.below(n);
            let len = rng.below(64).min(n - i);
            b.drain(i..i + len);
            "removed run"
        }
        _ => {
            let len = rng.below(4096);
            b = (0..len).map(|_| rng.next() as u8).collect();
            "random bytes"
        }
    };
    (what, b)
}

/// Numbers that sit at or past the edge of what a field may hold.
const EXTREME_NUMBERS: [&str; 12] = [
    "0",
    "-0",
    "-1",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "inf",
    "-inf",
    "9223372036854775808",
    "18446744073709551616",
    "1234567890123456789012345678901234567890",
];

/// Byte spans of the numbers in `text` (not those inside names such as `cmu_01_01`).
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let word = |c: u8| c.is_ascii_alphanumeric() || c == b'_' || c == b'.';
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let sign = matches!(b[i], b'-' | b'+') as usize;
        let starts = b.get(i + sign).is_some_and(u8::is_ascii_digit)
            && (i == 0 || !(word(b[i - 1]) || sign == 0 && matches!(b[i - 1], b'-' | b'+')));
        if !starts {
            i += 1;
            continue;
        }
        let mut j = i + sign;
        let digits = |j: &mut usize| {
            while b.get(*j).is_some_and(u8::is_ascii_digit) {
                *j += 1;
            }
        };
        digits(&mut j);
        if b.get(j) == Some(&b'.') {
            j += 1;
            digits(&mut j);
        }
        if matches!(b.get(j), Some(b'e' | b'E')) {
            let mut k = j + 1;
            if matches!(b.get(k), Some(b'-' | b'+')) {
                k += 1;
            }
            if b.get(k).is_some_and(u8::is_ascii_digit) {
                j = k;
                digits(&mut j);
            }
        }
        if !b
            .get(j)
            .is_some_and(|&c| c.is_ascii_alphabetic() || c == b'_')
        {
            spans.push((i, j));
        }
        i = j.max(i + 1);
    }
    spans
}

/// Byte spans of the values of quoted strings in `text` (between the quotes), or, in a format
/// without quotes, of the words after a line's first.
fn string_spans(text: &str) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut at = 0;
    for line in text.split_inclusive('\n') {
        let quotes: Vec<usize> = line.match_indices('"').map(|(i, _)| i).collect();
        for pair in quotes.chunks_exact(2) {
            spans.push((at + pair[0] + 1, at + pair[1]));
        }
        at += line.len();
    }
    if spans.is_empty() {
        at = 0;
        for line in text.split_inclusive('\n') {
            let mut words = line
                .match_indices(|c: char| !c.is_whitespace())
                .map(|(i, _)| i)
                .filter(|&i| i == 0 || line.as_bytes()[i - 1].is_ascii_whitespace());
            words.next();
            for i in words {
                let end = line[i..]
                    .find(char::is_whitespace)
                    .map_or(line.len(), |e| i + e);
                if number_spans(&line[i..end]).is_empty() {
                    spans.push((at + i, at + end));
                }
            }
            at += line.len();
        }
    }
    spans
}

/// `good` (text) with one token-level change of kind `kind` (0–5): a number made extreme
/// (twice as often as the others), a line duplicated, deleted or swapped with another, a
/// string value emptied.
fn token_damage(good: &str, rng: &mut Rng, kind: usize) -> (String, String) {
    let lines: Vec<&str> = good.split_inclusive('\n').collect();
    let n = lines.len();
    let splice = |(i, j): (usize, usize), with: &str| format!("{}{with}{}", &good[..i], &good[j..]);
    match kind % 6 {
        0 | 3 => {
            let spans = number_spans(good);
            if !spans.is_empty() {
                let span = spans[rng.below(spans.len())];
                let with = EXTREME_NUMBERS[rng.below(EXTREME_NUMBERS.len())];
                return (
                    format!("number `{}` → `{with}`", &good[span.0..span.1]),
                    splice(span, with),
                );
            }
        }
        1 => {
            let i = rng.below(n);
            let mut out = lines.clone();
            out.insert(i, lines[i]);
            return (format!("line {} twice", i + 1), out.concat());
        }
        2 => {
            let (i, j) = (rng.below(n), rng.below(n));
            let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
            // Each keeps its own line end, so that the last line (without one) joins none.
            let end = |l: &str| l.len() - l.trim_end_matches(['\n', '\r']).len();
            let (ei, ej) = (end(lines[i]), end(lines[j]));
            let (bi, bj) = (
                &lines[i][..lines[i].len() - ei],
                &lines[j][..lines[j].len() - ej],
            );
            out[i] = format!("{bj}{}", &lines[i][lines[i].len() - ei..]);
            out[j] = format!("{bi}{}", &lines[j][lines[j].len() - ej..]);
            return (
                format!("lines {} and {} swapped", i + 1, j + 1),
                out.concat(),
            );
        }
        4 => {
            let spans = string_spans(good);
            if !spans.is_empty() {
                let span = spans[rng.below(spans.len())];
                return (
                    format!("value `{}` emptied", &good[span.0..span.1]),
                    splice(span, ""),
                );
            }
        }
        _ => {}
    }
    let i = rng.below(n);
    let mut out = lines.clone();
    out.remove(i);
    (format!("line {} deleted", i + 1), out.concat())
}

/// Damaged versions of `good`, made one at a time (a long run of a large file would not fit in
/// memory at once): truncations, then byte-level changes, and for text half of them
/// token-level changes.
fn damaged(
    good: &[u8],
    seed: u64,
    text: bool,
    cases: usize,
) -> impl Iterator<Item = (String, Vec<u8>)> + '_ {
    let n = good.len();
    let cuts = [
        0,
        1,
        2,
        7,
        16,
        n / 10,
        n / 3,
        n / 2,
        n - n / 5,
        n.saturating_sub(1),
    ];
    let truncated = cuts
        .into_iter()
        .map(move |cut| (format!("first {cut} bytes"), good[..cut.min(n)].to_vec()));
    let text = text.then(|| std::str::from_utf8(good).expect("a text seed is UTF-8"));
    let mut rng = Rng(seed);
    let changed = (0..cases).map(move |case| match text {
        Some(t) if case % 2 == 1 => {
            let (what, b) = token_damage(t, &mut rng, case / 2);
            (format!("case {case}: {what}"), b.into_bytes())
        }
        _ => {
            let kind = if text.is_some() { case / 2 } else { case };
            let (what, b) = byte_damage(good, &mut rng, kind);
            (format!("case {case}: {what}"), b)
        }
    });
    truncated.chain(changed)
}

/// How one case ended.
enum Outcome {
    Readable,
    Refused(String),
    Panicked(String),
    Hung,
}

type ReadFn = Arc<dyn Fn(&Path) -> Result<(), String> + Send + Sync>;

/// Reads `path` on a thread of its own, waiting at most `deadline` (a thread past it is left
/// behind).
fn read_with_deadline(read: &ReadFn, path: PathBuf, deadline: Duration) -> Outcome {
    let (tx, rx) = mpsc::channel();
    let read = Arc::clone(read);
    std::thread::Builder::new()
        .name("fuzz case".into())
        .spawn(move || {
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| read(&path)));
            let _ = tx.send(result.map_err(|payload| {
                payload
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "(no message)".into())
            }));
        })
        .expect("starting a fuzz thread");
    match rx.recv_timeout(deadline) {
        Ok(Ok(Ok(()))) => Outcome::Readable,
        Ok(Ok(Err(message))) => Outcome::Refused(message),
        Ok(Err(message)) => Outcome::Panicked(message),
        Err(mpsc::RecvTimeoutError::Timeout) => Outcome::Hung,
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            Outcome::Panicked("the reader's thread ended without an answer".into())
        }
    }
}

/// One reader under test: the file damaged, files beside it left whole, and which of them the
/// reader is handed (the damaged one unless said).
struct Fuzz {
    name: String,
    good: Vec<u8>,
    seed: u64,
    text: bool,
    beside: Vec<(String, Vec<u8>)>,
    entry: Option<String>,
    /// Every damaged version may be read (a file the reader does without when it is unusable).
    all_may_read: bool,
    /// The cases, the deadline per case and the folder failing cases are kept in, when not the
    /// environment's.
    cases: Option<usize>,
    deadline: Option<Duration>,
    keep: Option<PathBuf>,
}

impl Fuzz {
    /// A binary file: byte-level changes only.
    fn bytes(name: &str, good: impl Into<Vec<u8>>, seed: u64) -> Fuzz {
        Fuzz {
            name: name.into(),
            good: good.into(),
            seed,
            text: false,
            beside: Vec::new(),
            entry: None,
            all_may_read: false,
            cases: None,
            deadline: None,
            keep: None,
        }
    }

    /// A text file: byte-level and token-level changes.
    fn text(name: &str, good: impl Into<Vec<u8>>, seed: u64) -> Fuzz {
        Fuzz {
            text: true,
            ..Fuzz::bytes(name, good, seed)
        }
    }

    /// A file written whole beside the damaged one.
    fn beside(mut self, name: &str, bytes: impl Into<Vec<u8>>) -> Fuzz {
        self.beside.push((name.into(), bytes.into()));
        self
    }

    /// The reader is handed `name` (one of the files beside), not the damaged file.
    fn through(mut self, name: &str) -> Fuzz {
        self.entry = Some(name.into());
        self
    }

    /// Every damaged version may be read: the reader does without the file when it is
    /// unusable.
    fn all_may_read(mut self) -> Fuzz {
        self.all_may_read = true;
        self
    }

    /// `cases` cases; those past `deadline` hang; failing cases are kept in `keep`.
    fn checked_with(mut self, cases: usize, deadline: Duration, keep: &Path) -> Fuzz {
        self.cases = Some(cases);
        self.deadline = Some(deadline);
        self.keep = Some(keep.to_owned());
        self
    }

    /// Feeds every damaged version to `read`; fails naming each case that panicked, hung or
    /// was refused without naming the file handed to the reader, its files kept.
    fn run<T, E: Display>(self, read: impl Fn(&Path) -> Result<T, E> + Send + Sync + 'static) {
        let read: ReadFn = Arc::new(move |p: &Path| read(p).map(|_| ()).map_err(|e| e.to_string()));
        let entry = self.entry.clone().unwrap_or_else(|| self.name.clone());
        let label = match &self.entry {
            Some(e) => format!("{e} (its {} damaged)", self.name),
            None => self.name.clone(),
        };
        let dir = tempfile::tempdir().unwrap();
        let deadline = self.deadline.unwrap_or_else(deadline);
        let keep = self.keep.clone().unwrap_or_else(keep_dir);
        let start = Instant::now();
        let (mut readable, mut refused, mut hangs, mut count) = (0, 0, 0, 0);
        let mut failures = Vec::new();
        for (k, (what, bytes)) in damaged(
            &self.good,
            self.seed,
            self.text,
            self.cases.unwrap_or_else(cases),
        )
        .enumerate()
        {
            // Each case in a folder of its own: a reader left hanging may still read its files.
            let case_dir = dir.path().join(format!("case_{k}"));
            std::fs::create_dir(&case_dir).unwrap();
            for (name, b) in &self.beside {
                std::fs::write(case_dir.join(name), b).unwrap();
            }
            std::fs::write(case_dir.join(&self.name), &bytes).unwrap();
            count += 1;
            let failure = match read_with_deadline(&read, case_dir.join(&entry), deadline) {
                Outcome::Readable => {
                    readable += 1;
                    None
                }
                Outcome::Refused(msg) => {
                    refused += 1;
                    // The file handed to the reader, or the damaged one beside it.
                    (!msg.contains(&entry) && !msg.contains(&self.name))
                        .then(|| format!("the error does not name the file: {msg}"))
                }
                Outcome::Panicked(msg) => Some(format!("the reader panicked: {msg}")),
                Outcome::Hung => {
                    hangs += 1;
                    Some(format!("no answer within {deadline:?}"))
                }
            };
            if let Some(failure) = failure {
                let kept = keep.join(slug(&label)).join(slug(&what));
                let _ = std::fs::remove_dir_all(&kept);
                std::fs::create_dir_all(&kept).unwrap();
                for (name, b) in self.beside.iter().chain([&(self.name.clone(), bytes)]) {
                    std::fs::write(kept.join(name), b).unwrap();
                }
                let line = format!("{label}, {what}: {failure} (kept in {})", kept.display());
                std::fs::write(kept.join("what.txt"), format!("{line}\n")).unwrap();
                eprintln!("{line}");
                failures.push(line);
            }
            if hangs >= MAX_HANGS {
                failures.push(format!("{label}: stopped after {hangs} hangs"));
                break;
            }
            let _ = std::fs::remove_dir_all(&case_dir);
        }
        let seconds = start.elapsed().as_secs_f64();
        println!(
            "fuzz {label}: {count} cases, {refused} refused, {readable} still readable, {seconds:.1} s"
        );
        assert!(
            failures.is_empty(),
            "{label}: {} failing cases:\n{}",
            failures.len(),
            failures.join("\n")
        );
        assert!(
            refused > 0 || self.all_may_read,
            "{label}: no damaged version was refused"
        );
    }
}

/// A reader that hangs, panics or answers without naming the file fails the run, naming the
/// reader and the case, with the case's files kept; a hanging reader is given up after
/// [`MAX_HANGS`] hangs.
#[test]
fn readers_that_hang_panic_or_do_not_name_the_file_fail_the_run() {
    let keep = tempfile::tempdir().unwrap();
    let failure = |read: fn(&Path) -> Result<(), String>| {
        let run = std::panic::catch_unwind(|| {
            Fuzz::text("stuck.toml", "a = 1\nb = \"x\"\n", 31)
                .checked_with(8, Duration::from_millis(200), keep.path())
                .run(read)
        });
        let payload = run.expect_err("the run passed");
        payload.downcast_ref::<String>().cloned().unwrap()
    };
    let msg = failure(|p| match std::fs::read(p).unwrap().len() {
        0 => loop {
            std::thread::park();
        },
        _ => Ok(()),
    });
    assert!(
        msg.contains("stuck.toml, first 0 bytes: no answer within 200ms"),
        "{msg}"
    );
    let kept = keep.path().join("stuck_toml").join("first_0_bytes");
    assert_eq!(std::fs::read(kept.join("stuck.toml")).unwrap(), b"");
    assert!(std::fs::read_to_string(kept.join("what.txt"))
        .unwrap()
        .contains("no answer"));

    let msg = failure(|_| loop {
        std::thread::park();
    });
    assert!(msg.contains("stuck.toml: stopped after 3 hangs"), "{msg}");

    let msg = failure(|p| match std::fs::read(p).unwrap().len() {
        1 => panic!("index out of range"),
        _ => Err(format!("{}: bad", p.display())),
    });
    assert!(
        msg.contains("stuck.toml, first 1 bytes: the reader panicked: index out of range"),
        "{msg}"
    );
    let msg = failure(|_| Err("bad value".into()));
    assert!(
        msg.contains("the error does not name the file: bad value"),
        "{msg}"
    );
}

/// `what` as a folder name.
fn slug(what: &str) -> String {
    let s: String = what
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    s.chars().take(80).collect()
}

fn read(p: &str) -> Vec<u8> {
    std::fs::read(root().join(p)).unwrap()
}

/// A shipped config's text with its paths into the repository (`"../assets/…"`,
/// `"../camera_rigs/…"`) made absolute, so that changed versions get past the files they name
/// when read from a temporary folder; output folders stay relative (inside that folder).
fn shipped_config(p: &str) -> String {
    let r = root().display().to_string();
    String::from_utf8(read(p))
        .unwrap()
        .replace("\"../assets/", &format!("\"{r}/assets/"))
        .replace("\"../camera_rigs/", &format!("\"{r}/camera_rigs/"))
}

#[test]
fn run_configs() {
    let resolve = |p: &Path| {
        egogen::cli::config::RawRun::load(p)
            .and_then(|raw| egogen::cli::resolve::resolve_run(raw, p))
    };
    Fuzz::text("run.toml", shipped_config("configs/default.toml"), 1).run(resolve);
    Fuzz::text(
        "activities.toml",
        shipped_config("configs/activities.toml"),
        16,
    )
    .run(resolve);
}

#[test]
fn synth_config() {
    Fuzz::text("crowd4.toml", shipped_config("configs/crowd4.toml"), 17)
        .run(egogen::cli::synth_config::load_synth_plan);
    Fuzz::text(
        "apartment3.toml",
        shipped_config("configs/apartment3.toml"),
        18,
    )
    .run(egogen::cli::synth_config::load_synth_plan);
}

#[test]
fn campaign_config() {
    let r = root().display().to_string();
    let text = shipped_config("configs/campaign.toml").replace(
        "run = \"default.toml\"",
        &format!("run = \"{r}/configs/default.toml\""),
    );
    Fuzz::text("campaign.toml", text, 19).run(egogen::campaign::plan::plan_campaign);
}

/// `scene generate --settings`: settings accepted must make a dwelling or say why not (a
/// failure to draw one is the generator's answer, not the file's, so it is named with the file
/// here), never panic or hang.
#[test]
fn dwelling_settings() {
    use egogen::scene::dwelling::{generate, shipped_catalogue_dir, Catalogue, DwellingSettings};
    let catalogue = Arc::new(Catalogue::load(&shipped_catalogue_dir()).unwrap());
    let defaults = toml::to_string(&DwellingSettings::default()).unwrap();
    Fuzz::text("dwelling.toml", defaults, 20).run(move |p| {
        let settings = egogen::cli::scene_jobs::load_dwelling_settings(p)?;
        generate(&settings, &catalogue, 0)
            .map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))
            .map(|_| ())
    });
}

/// `scene generate --catalogue`: the shipped furniture catalogue (its model files named by
/// absolute path, so that the catalogue may lie in another folder); a catalogue accepted must
/// make a dwelling or say why not, never panic or hang.
#[test]
fn furniture_catalogue() {
    use egogen::scene::dwelling::{generate, shipped_catalogue_dir, Catalogue, DwellingSettings};
    let dir = shipped_catalogue_dir().display().to_string();
    let text = String::from_utf8(read("assets/furniture/catalogue.json"))
        .unwrap()
        .replace("\"file\": \"", &format!("\"file\": \"{dir}/"));
    Fuzz::text("catalogue.json", text, 29).run(|p| {
        let catalogue = Catalogue::load(p.parent().unwrap())?;
        generate(&DwellingSettings::default(), &catalogue, 0)
            .map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))
            .map(|_| ())
    });
}

#[test]
fn pose_prior() {
    Fuzz::text("pose_prior.json", read("assets/policy/pose_prior.json"), 30)
        .run(egogen::walker::PosePrior::load);
}

/// Dwelling settings at the largest values taken make a dwelling or say why not, never panic
/// (`aspect = [1.0, 1e308]` laid walls out at infinite coordinates); past them they are refused
/// naming the file and the key.
#[test]
fn dwelling_settings_at_their_limits_make_a_dwelling_or_say_why_not() {
    use egogen::cli::scene_jobs::load_dwelling_settings;
    use egogen::scene::dwelling::{generate, shipped_catalogue_dir, Catalogue};
    let catalogue = Catalogue::load(&shipped_catalogue_dir()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for (key, at_limit, past) in [
        ("aspect", "[1.0, 10.0]", "[1.0, 1e308]"),
        ("bedroom_m2", "[9.0, 500.0]", "[9.0, 1e308]"),
        ("living_m2", "[18.0, 500.0]", "[18.0, 501.0]"),
        ("ceiling_m", "[2.5, 10.0]", "[2.5, 10.5]"),
        ("window_sill_m", "[0.9, 1.0]", "[0.9, inf]"),
    ] {
        let path = dir.path().join(format!("{key}.toml"));
        std::fs::write(&path, format!("{key} = {past}\n")).unwrap();
        let err = load_dwelling_settings(&path).unwrap_err().to_string();
        assert!(
            err.contains(&format!("{key}.toml")) && err.contains(&format!("`{key}`")),
            "{err}"
        );
        std::fs::write(&path, format!("{key} = {at_limit}\n")).unwrap();
        let settings = load_dwelling_settings(&path).unwrap();
        for seed in 0..3 {
            let _ = generate(&settings, &catalogue, seed);
        }
    }
}

#[test]
fn rig_and_aria_calibration() {
    Fuzz::text("rig.json", read("camera_rigs/aria_gen1.json"), 2).run(Rig::load);
    Fuzz::text("hololens2.json", read("camera_rigs/hololens2.json"), 21).run(Rig::load);
    Fuzz::text(
        "calibration.json",
        read("tests/fixtures/aria_gen1_device_calibration.json"),
        3,
    )
    .run(Rig::load);
}

#[test]
fn body_model_npz() {
    Fuzz::bytes("body.npz", read("assets/body/SMPLX_NEUTRAL.npz"), 4).run(|p| BodyModel::load(p));
}

#[test]
fn motion_npz() {
    Fuzz::bytes("motion.npz", read("assets/motion/cmu_01_01.npz"), 5).run(MotionSequence::read);
}

#[test]
fn bvh() {
    Fuzz::text("clip.bvh", read("tests/fixtures/cmu_01_01_excerpt.bvh"), 6).run(BvhClip::read);
}

#[test]
fn mps_trajectory() {
    // The first 200 poses of the shipped MPS sample.
    let csv = String::from_utf8(read(
        "assets/reference/aria_mps_sample_closed_loop_trajectory.csv",
    ))
    .unwrap();
    let head: String = csv.split_inclusive('\n').take(201).collect();
    Fuzz::text("trajectory.csv", head, 22).run(egogen::motion::head_motion::read_mps_trajectory);
}

/// A frame of a humanoid3d clip: duration, root position, 8 quaternions, 4 angles.
fn deepmimic_frame(x: f64) -> Vec<f64> {
    let mut f = vec![0.0333, x, 0.85, 0.0];
    for k in 0..15 {
        if [4, 8, 11, 14].contains(&k) {
            f.push(0.1);
        } else {
            f.extend([1.0, 0.0, 0.0, 0.0]);
        }
    }
    f.truncate(44);
    f
}

fn deepmimic_clip(frames: &[Vec<f64>]) -> String {
    serde_json::to_string_pretty(&serde_json::json!({"Loop": "wrap", "Frames": frames})).unwrap()
}

#[test]
fn deepmimic() {
    let model = Arc::new(BodyModel::load(root().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap());
    let good = deepmimic_clip(&[deepmimic_frame(0.0), deepmimic_frame(0.05)]);
    Fuzz::text("walk.txt", good, 7).run(move |p| import_deepmimic(p, &model));
}

/// A DeepMimic clip with a rotation of no length (a quaternion of zeros, or one too small or
/// too large to normalise) or a frame duration too short for a rate is refused naming the file,
/// the frame and the rotation, not with a retargeting error that names none.
#[test]
fn a_deepmimic_clip_without_a_rotation_is_refused_naming_the_file() {
    let model = BodyModel::load(root().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for (k, at, value, needle) in [
        (0, 4, 0.0, "frame 1: the root rotation"),
        (1, 21, 1e-320, "frame 1: the right ankle rotation"),
        (2, 12, 1e308, "frame 1: the neck rotation"),
        (4, 0, 1e-320, "frame duration"),
    ] {
        // The clip's rate is its first frame's duration; the rest changes the second frame.
        let mut frames = [deepmimic_frame(0.0), deepmimic_frame(0.05)];
        frames[(at > 0) as usize][at] = value;
        let path = dir.path().join(format!("clip_{k}.txt"));
        std::fs::write(&path, deepmimic_clip(&frames)).unwrap();
        let err = import_deepmimic(&path, &model)
            .err()
            .unwrap_or_else(|| panic!("number {at} = {value} accepted"))
            .to_string();
        assert!(
            err.contains(&format!("clip_{k}.txt")) && err.contains(needle),
            "{err}"
        );
    }
}

fn scene(p: &Path) -> Result<egogen::scene::SceneMesh, egogen::scene::SceneError> {
    load_scene(p, Default::default())
}

#[test]
fn glb_scene() {
    Fuzz::bytes("room.glb", read("assets/scenes/apartment.glb"), 8).run(scene);
}

/// The shipped apartment as a `.gltf` (its JSON chunk, indented, its buffer pointing at a
/// `.bin` beside it) and that `.bin` (the GLB's binary chunk).
fn apartment_as_gltf(bin_name: &str) -> (String, Vec<u8>) {
    let glb = read("assets/scenes/apartment.glb");
    let chunk = |at: usize| {
        let len = u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
        (&glb[at + 8..at + 8 + len], at + 8 + len)
    };
    let (json, next) = chunk(12);
    let (bin, _) = chunk(next);
    let mut doc: serde_json::Value = serde_json::from_slice(json).unwrap();
    doc["buffers"][0]["uri"] = serde_json::json!(bin_name);
    (serde_json::to_string_pretty(&doc).unwrap(), bin.to_vec())
}

#[test]
fn gltf_scene() {
    let (json, bin) = apartment_as_gltf("room.bin");
    Fuzz::text("room.gltf", json.clone(), 23)
        .beside("room.bin", bin.clone())
        .run(scene);
    Fuzz::bytes("room.bin", bin, 24)
        .beside("room.gltf", json)
        .through("room.gltf")
        .run(scene);
}

/// The shipped stepped house with a material library: each object uses one of [`MTL`]'s
/// materials in turn.
fn stepped_house_with_materials() -> String {
    let obj = String::from_utf8(read("assets/scenes/stepped_house.obj")).unwrap();
    let materials = ["plaster", "wood", "glass", "tiles"];
    let mut out = String::from("mtllib room.mtl\n");
    let mut k = 0;
    for line in obj.split_inclusive('\n') {
        out.push_str(line);
        if line.starts_with("o ") {
            out.push_str(&format!("usemtl {}\n", materials[k % materials.len()]));
            k += 1;
        }
    }
    out
}

/// A material library as exporters write one: colours, a texture, a see-through material.
const MTL: &str = "# materials of the stepped house
newmtl plaster
Ns 10.0
Ka 1.000 1.000 1.000
Kd 0.800 0.780 0.750
Ks 0.050 0.050 0.050
Ni 1.45
d 1.0
illum 2

newmtl wood
Kd 0.55 0.35 0.20
map_Kd textures/oak_diffuse.png
map_Bump -bm 0.5 textures/oak_normal.png
illum 2

newmtl glass
Kd 0.9 0.95 1.0
d 0.25
Tr 0.75
illum 4

newmtl tiles
Kd 0.7 0.7 0.7
map_Kd -s 2.0 2.0 1.0 textures/tiles.jpg
map_d textures/tiles_alpha.png
illum 1
";

#[test]
fn obj_scene() {
    let obj = stepped_house_with_materials();
    Fuzz::text("room.obj", obj.clone(), 9)
        .beside("room.mtl", MTL)
        .run(scene);
    // An unusable material library leaves the faces untextured, as Blender's importer does.
    Fuzz::text("room.mtl", MTL, 25)
        .beside("room.obj", obj)
        .through("room.obj")
        .all_may_read()
        .run(scene);
}

/// A material library tobj cannot parse (a colour of two numbers, on which tobj panics) leaves
/// the faces untextured, as a missing one does.
#[test]
fn an_unparsable_material_library_is_done_without() {
    let dir = tempfile::tempdir().unwrap();
    let obj = stepped_house_with_materials();
    std::fs::write(dir.path().join("room.obj"), &obj).unwrap();
    std::fs::write(
        dir.path().join("room.mtl"),
        MTL.replace("Ks 0.050 0.050 0.050", "Ks 0.050 0"),
    )
    .unwrap();
    let mesh = scene(&dir.path().join("room.obj")).unwrap();
    assert!(mesh.objects.iter().all(|o| !o.textured && !o.see_through));
    std::fs::write(dir.path().join("room.mtl"), MTL).unwrap();
    let mesh = scene(&dir.path().join("room.obj")).unwrap();
    assert!(mesh.objects.iter().any(|o| o.textured) && mesh.objects.iter().any(|o| o.see_through));
}

#[test]
fn ply_scene() {
    let ply = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n4 0 0\n4 0 4\n0 0 4\n3 0 1 2\n3 0 2 3\n";
    Fuzz::text("room.ply", ply.to_vec(), 10).run(scene);
}

/// A scan as Replica ships one: faces with an `object_id`, their classes in
/// `info_semantic.json` beside it; written binary (little-endian) as scanners write them.
fn replica_scan() -> (Vec<u8>, String) {
    let verts: [[f32; 3]; 6] = [
        [0.0, 0.0, 0.0],
        [4.0, 0.0, 0.0],
        [4.0, 4.0, 0.0],
        [0.0, 4.0, 0.0],
        [1.0, 1.0, 0.8],
        [2.0, 1.0, 0.8],
    ];
    let faces: [(&[i32], i32); 3] = [(&[0, 1, 2, 3], 1), (&[0, 2, 3], 1), (&[3, 4, 5], 7)];
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\ncomment Replica-style scan\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nproperty uchar red\n\
         property uchar green\nproperty uchar blue\nelement face {}\n\
         property list uchar int vertex_indices\nproperty int object_id\nend_header\n",
        verts.len(),
        faces.len()
    )
    .into_bytes();
    for v in verts {
        for c in v {
            b.extend(c.to_le_bytes());
        }
        b.extend([200, 180, 160]);
    }
    for (idx, id) in faces {
        b.push(idx.len() as u8);
        for i in idx {
            b.extend(i.to_le_bytes());
        }
        b.extend(id.to_le_bytes());
    }
    let labels = serde_json::json!({"objects": [
        {"id": 1, "class_name": "floor"},
        {"id": 7, "class_name": "table"},
        {"id": 9, "class_name": null},
    ]});
    (b, serde_json::to_string_pretty(&labels).unwrap())
}

#[test]
fn ply_scan_with_labels() {
    let (ply, labels) = replica_scan();
    Fuzz::bytes("scan.ply", ply.clone(), 26)
        .beside("info_semantic.json", labels.clone())
        .run(scene);
    Fuzz::text("info_semantic.json", labels, 27)
        .beside("scan.ply", ply)
        .through("scan.ply")
        .run(scene);
}

/// Random bytes under a scene's name are refused with what the file should have been, not
/// only the parser's words.
#[test]
fn random_bytes_as_a_scene_say_what_the_file_should_be() {
    let dir = tempfile::tempdir().unwrap();
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let bytes: Vec<u8> = (0..4096)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect();
    for (name, format) in [
        ("scan.glb", "glTF"),
        ("scan.gltf", "glTF"),
        ("scan.obj", "Wavefront OBJ"),
        ("scan.ply", "PLY"),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).unwrap();
        let msg = load_scene(&path, Default::default())
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains(&path.display().to_string())
                && msg.contains(&format!("not a valid {format} file"))
                && msg.contains("check that the file is complete"),
            "{name}: {msg}"
        );
    }
}

#[test]
fn exr() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("good.exr");
    write_rgba_file(&path, 16, 8, |x, y| {
        (x as f32 / 16.0, y as f32 / 8.0, 0.5f32, 1.0f32)
    })
    .unwrap();
    Fuzz::bytes("frame.exr", std::fs::read(&path).unwrap(), 11).run(ExrContents::read);
}

#[test]
fn weights_files() {
    Fuzz::bytes(
        "motion.safetensors",
        read("assets/motion/primitive_cvae.safetensors"),
        12,
    )
    .run(egogen::motion::cvae::weights::read_arch);
    Fuzz::bytes(
        "policy.safetensors",
        read("assets/policy/policy.safetensors"),
        13,
    )
    .run(|p| {
        egogen::policy::weights::load_policy::<egogen::motion::cvae::infer::InferBackend>(
            p,
            &Default::default(),
        )
    });
}

/// `configs/train_policy.toml` with its paths made absolute, so that changed versions get past
/// the files they name.
fn training_config() -> String {
    String::from_utf8(read("configs/train_policy.toml"))
        .unwrap()
        .replace("\"../", &format!("\"{}/", root().display()))
        .replace(
            "\"train_primitive.toml",
            &format!("\"{}/configs/train_primitive.toml", root().display()),
        )
}

#[test]
fn training_configs() {
    Fuzz::text("train_policy.toml", training_config(), 14)
        .run(egogen::cli::train_policy::load_policy_plan);
    Fuzz::text(
        "train_primitive.toml",
        shipped_config("configs/train_primitive.toml"),
        28,
    )
    .run(egogen::cli::train_primitive::load_train_plan);
}

#[test]
fn point_cache() {
    use egogen::vertex_cache::PointCache;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("good.pc2");
    let cache = PointCache {
        start_frame: 0.0,
        sample_rate: 1.0,
        samples: vec![vec![[0.0, 1.0, 2.0]; 5]; 3],
    };
    cache.write(&path).unwrap();
    Fuzz::bytes("body.pc2", std::fs::read(&path).unwrap(), 15).run(PointCache::read);
}

/// The error of loading the shipped policy written to `dir/name.safetensors` with its header's
/// architecture changed by `claims`.
fn load_policy_claiming(dir: &Path, name: &str, claims: &[(&str, u64)]) -> String {
    let good = read("assets/policy/policy.safetensors");
    let n = u64::from_le_bytes(good[..8].try_into().unwrap()) as usize;
    let mut header: serde_json::Value = serde_json::from_slice(&good[8..8 + n]).unwrap();
    let arch = header["__metadata__"]["egogen.policy_arch"]
        .as_str()
        .unwrap()
        .to_owned();
    let mut arch: serde_json::Value = serde_json::from_str(&arch).unwrap();
    for (key, value) in claims {
        arch[*key] = serde_json::json!(value);
    }
    header["__metadata__"]["egogen.policy_arch"] = serde_json::json!(arch.to_string());
    let mut bytes = serde_json::to_vec(&header).unwrap();
    let mut file = (bytes.len() as u64).to_le_bytes().to_vec();
    file.append(&mut bytes);
    file.extend_from_slice(&good[8 + n..]);
    let path = dir.join(format!("{name}.safetensors"));
    std::fs::write(&path, file).unwrap();
    match egogen::policy::weights::load_policy::<egogen::motion::cvae::infer::InferBackend>(
        &path,
        &Default::default(),
    ) {
        Ok(_) => panic!("{name}: a policy claiming {claims:?} was loaded"),
        Err(e) => e.to_string(),
    }
}

/// Sizes that scale memory are refused by key, before anything is allocated — never an abort
/// (`memory allocation failed`, which ends this test process): a policy file whose header
/// claims a huge network, training configs asking for one or for huge batches, a synth crowd of
/// 10¹³ people or 10¹² shape coefficients, `policy eval --episodes 1e12`.
#[test]
fn sizes_that_would_exhaust_memory_are_refused_by_key() {
    let dir = tempfile::tempdir().unwrap();
    // The shipped policy with its header's architecture claiming hidden = 10⁹.
    let err = load_policy_claiming(dir.path(), "huge_policy", &[("hidden", 1_000_000_000)]);
    assert!(
        err.contains("huge_policy.safetensors") && err.contains("hidden"),
        "{err}"
    );

    // Training configs.
    let text = training_config();
    for (section, key, value) in [
        ("[policy]", "hidden", "1000000000"),
        ("[ppo]", "envs", "1000000000000"),
        ("[validation]", "episodes", "1000000000000"),
    ] {
        let config = dir.path().join(format!("train_{key}.toml"));
        let changed = format!("{section}\n{key} = {value}");
        let body = if text.contains(&format!("\n{key} =")) {
            text.lines()
                .filter(|l| !l.starts_with(&format!("{key} =")))
                .collect::<Vec<_>>()
                .join("\n")
        } else {
            text.clone()
        };
        std::fs::write(&config, body.replacen(section, &changed, 1)).unwrap();
        let err = egogen::cli::train_policy::load_policy_plan(&config)
            .err()
            .unwrap_or_else(|| panic!("{key} = {value} accepted"))
            .to_string();
        assert!(
            err.contains(key) && err.contains(&format!("train_{key}.toml")),
            "{err}"
        );
    }

    // A synth crowd.
    for (key, line) in [
        ("crowd.count", "count = 10000000000000"),
        (
            "crowd.betas_count",
            "count = 3\nbetas_count = 1000000000000",
        ),
    ] {
        let config = dir.path().join("synth.toml");
        std::fs::write(
            &config,
            format!(
                "[scene]\nfloor_m = 8.0\n[motion]\nduration_s = 1.0\n[crowd]\n{line}\nlayout = \"random\"\nsteering = \"sampling\"\nk = 2\n[output]\ndir = \"out\"\n"
            ),
        )
        .unwrap();
        let err = egogen::cli::synth_config::load_synth_plan(&config)
            .err()
            .unwrap_or_else(|| panic!("{line} accepted"))
            .to_string();
        assert!(err.contains(key), "{err}");
    }

    // policy eval.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["policy", "eval", "--episodes", "1000000000000"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--episodes"), "{err}");
}

/// Sizes each within its key's fixed limit whose product would not fit in memory are refused
/// before anything is allocated, naming the key, what they need and the budget: a training
/// rollout, a policy file's network, a synth crowd, a scene's walkable map and `egogen-run`'s
/// scripted walk under a small `EGOGEN_MEMORY_GB`.
#[test]
fn sizes_within_their_limits_that_would_not_fit_in_memory_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    // 65 536 environments × 4 096 steps: each key within its limit, the rollout hundreds of GB.
    let text = training_config();
    let config = dir.path().join("train_rollout.toml");
    let body: String = text
        .lines()
        .filter(|l| !l.starts_with("envs =") && !l.starts_with("steps_per_env ="))
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(
        &config,
        body.replacen("[ppo]", "[ppo]\nenvs = 65536\nsteps_per_env = 4096", 1),
    )
    .unwrap();
    let err = egogen::cli::train_policy::load_policy_plan(&config)
        .expect_err("a rollout of 2.7e8 steps was accepted")
        .to_string();
    assert!(
        err.contains("ppo.envs") && err.contains("train_rollout.toml") && err.contains("GB"),
        "{err}"
    );

    // A policy file whose header asks for hidden = 4 096 with 64 residual blocks (each within
    // its limit): a network of 69 GB.
    let err = load_policy_claiming(
        dir.path(),
        "wide_policy",
        &[("hidden", 4096), ("residual_blocks", 64)],
    );
    assert!(
        err.contains("wide_policy.safetensors") && err.contains("hidden = 4096"),
        "{err}"
    );

    // A crowd of 32 agents for 10 minutes under a 1 GB budget; a budget that is not a number.
    let synth = |budget: &str| {
        let config = dir.path().join("synth_memory.toml");
        std::fs::write(
            &config,
            "[scene]\nfloor_m = 8.0\n[motion]\nduration_s = 600.0\n[crowd]\ncount = 32\nbetas_count = 300\nlayout = \"random\"\nsteering = \"sampling\"\nk = 2\n[output]\ndir = \"out\"\n",
        )
        .unwrap();
        std::process::Command::new(env!("CARGO_BIN_EXE_egogen"))
            .args(["synth", "--quiet"])
            .arg(&config)
            .env("EGOGEN_MEMORY_GB", budget)
            .output()
            .unwrap()
    };
    let out = synth("1");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("motion.duration_s")
            && err.contains("32 agents × 24014 frames")
            && err.contains("EGOGEN_MEMORY_GB"),
        "{err}"
    );
    let out = synth("lots");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("EGOGEN_MEMORY_GB = \"lots\""),
        "{err}"
    );

    // A 300 m square floor scene: its walkable map (9 · 10⁶ cells, within the cell limit) needs
    // 279 MB, refused under 0.1 GB naming the scene file.
    std::fs::write(
        dir.path().join("floor.obj"),
        "v -150 -150 0\nv 150 -150 0\nv 150 150 0\nv -150 150 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let config = dir.path().join("synth_floor.toml");
    std::fs::write(
        &config,
        "[scene]\npath = \"floor.obj\"\n[motion]\nduration_s = 1.0\n[crowd]\ncount = 1\nlayout = \"random\"\nsteering = \"sampling\"\nk = 2\n[output]\ndir = \"out\"\n",
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["synth", "--quiet"])
        .arg(&config)
        .env("EGOGEN_MEMORY_GB", "0.1")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("floor.obj") && err.contains("3002 × 3002 cells") && err.contains("279 MB"),
        "{err}"
    );
    assert!(!dir.path().join("out").exists() && !dir.path().join("out.partial").exists());

    // egogen-run's scripted walk at its frame limit (10⁶ frames) under a 1 GB budget.
    let config = dir.path().join("walk.toml");
    std::fs::write(
        &config,
        "[body]\nbetas = []\n[motion]\nsource = \"scripted_walk\"\nduration_s = 25000.0\n\
         frame_rate_hz = 40.0\n[output]\ndir = \"walk\"\n",
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_egogen-run"))
        .arg(&config)
        .env("EGOGEN_MEMORY_GB", "1")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("motion.duration_s") && err.contains("a scripted walk of 1000000 frames"),
        "{err}"
    );
    assert!(!dir.path().join("walk").exists() && !dir.path().join("walk.partial").exists());
}
