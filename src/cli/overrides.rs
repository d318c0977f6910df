//! `egogen-run`'s command-line overrides, applied in one place: to the config as written,
//! before it is resolved and checked (so every value passes the same checks as one written in
//! the file), and the effective config a dataset records and a resume compares.

use std::path::{Path, PathBuf};

use super::config::{Backend, MotionSource, RawRun};

/// What the command line overrides.
#[derive(Debug, Clone, Default)]
pub(crate) struct RunOverrides {
    /// `output.dir`.
    pub out: Option<PathBuf>,
    /// Every seed of the config: `motion.seed` (agents) or `scene.seed` (a placed motion),
    /// `[render.skin]`'s and `[render.outfits]`', and those of `[render.lighting]`, `[render.materials]`,
    /// `[render.headset_wear]` and `[render.depth_noise]` where those sections are given —
    /// another variant of the same config.
    pub seed: Option<u64>,
    /// `render.rig`.
    pub rig: Option<PathBuf>,
    /// `scene.path`.
    pub scene: Option<PathBuf>,
    /// `scene.up_axis`: which axis of the scene file points up.
    pub up_axis: Option<crate::scene::UpAxis>,
    /// `scene.unit_m`: metres per unit of the scene file.
    pub unit_m: Option<f64>,
    /// `crowd.count` (a config with a `[crowd]`).
    pub crowd_count: Option<usize>,
    /// `motion.duration_s`.
    pub duration_s: Option<f64>,
    /// `activities.weights`: what people do when a walk ends.
    pub activity_weights: Option<crate::synth::activity::ActivityWeights>,
    /// `render.materials.mode`.
    pub materials: Option<crate::render::materials::MaterialsMode>,
    /// `supervisor.workers`.
    pub workers: Option<usize>,
    /// `supervisor.backend`.
    pub backend: Option<Backend>,
}

impl RunOverrides {
    /// Applies the overrides to a config as written; paths given on the command line are made
    /// absolute (the config's own stay relative to its folder).
    pub(crate) fn apply(&self, raw: &mut RawRun) -> anyhow::Result<()> {
        use anyhow::Context;
        let absolute = |p: &Path| {
            std::path::absolute(p)
                .with_context(|| format!("resolving {} given on the command line", p.display()))
        };
        if let Some(out) = &self.out {
            raw.output.dir = absolute(out)?;
        }
        if let Some(rig) = &self.rig {
            raw.render.get_or_insert_with(Default::default).rig = Some(absolute(rig)?);
        }
        if let Some(scene) = &self.scene {
            raw.scene.path = Some(absolute(scene)?);
        }
        if let Some(up) = self.up_axis {
            raw.scene.up_axis = Some(up);
        }
        if let Some(unit) = self.unit_m {
            raw.scene.unit_m = Some(unit);
        }
        if let Some(count) = self.crowd_count {
            let Some(crowd) = raw.crowd.as_mut() else {
                anyhow::bail!(
                    "--crowd-count {count}: the config has no [crowd] section to set `crowd.count` in"
                );
            };
            crowd.count = count;
        }
        if let Some(d) = self.duration_s {
            raw.motion.duration_s = Some(d);
        }
        if let Some(w) = self.activity_weights {
            raw.activities.weights = w;
        }
        if let Some(mode) = self.materials {
            let Some(r) = raw.render.as_mut() else {
                anyhow::bail!(
                    "--materials: the config has no [render] section; nothing is rendered"
                );
            };
            r.materials
                .get_or_insert(super::config::RawMaterials {
                    mode: None,
                    seed: None,
                })
                .mode = Some(mode);
        }
        if let Some(seed) = self.seed {
            // Agents draw from the motion's seed; a single motion is placed by the scene's.
            if raw.motion.source == MotionSource::Agents {
                raw.motion.seed = Some(seed);
            } else {
                raw.scene.seed = Some(seed);
            }
            if let Some(r) = raw.render.as_mut() {
                if let Some(l) = r.lighting.as_mut() {
                    l.seed = Some(seed);
                }
                if let Some(w) = r.headset_wear.as_mut() {
                    w.seed = Some(seed);
                }
                if let Some(m) = r.materials.as_mut() {
                    m.seed = Some(seed);
                }
                if let Some(d) = r.depth_noise.as_mut() {
                    d.seed = Some(seed);
                }
                // Skin and outfits are always drawn: a new seed gives new ones.
                r.skin.get_or_insert_with(Default::default).seed = Some(seed);
                r.outfits.get_or_insert_with(Default::default).seed = Some(seed);
            }
        }
        if let Some(w) = self.workers {
            raw.supervisor.workers = Some(w);
        }
        if let Some(b) = self.backend {
            raw.supervisor.backend = Some(b);
            // Slurm resources stay in the record but only the Slurm backend reads them.
            if b != Backend::Slurm {
                raw.supervisor.slurm = None;
            }
        }
        Ok(())
    }

    /// The flags given that change what is rendered (all but `--workers` and `--backend`).
    pub(crate) fn take_flags(&self) -> Vec<&'static str> {
        [
            ("--out", self.out.is_some()),
            ("--seed", self.seed.is_some()),
            ("--rig", self.rig.is_some()),
            ("--scene", self.scene.is_some()),
            ("--up", self.up_axis.is_some()),
            ("--unit-m", self.unit_m.is_some()),
            ("--crowd-count", self.crowd_count.is_some()),
            ("--duration", self.duration_s.is_some()),
            ("--activity-weights", self.activity_weights.is_some()),
            ("--materials", self.materials.is_some()),
        ]
        .into_iter()
        .filter_map(|(flag, on)| on.then_some(flag))
        .collect()
    }
}

/// The config's values without `[supervisor]` (how many workers ran where does not change
/// what is rendered: a dataset rendered locally and one rendered on Slurm are the same).
fn content_table(raw: &RawRun) -> Result<toml::Table, toml::ser::Error> {
    let mut table = toml::Table::try_from(raw)?;
    table.remove("supervisor");
    Ok(table)
}

/// The effective config as TOML, for the dataset's `config.toml`: the file's values with the
/// overrides applied, `[supervisor]` left out (the logs record how the shards ran), relative
/// paths still relative to the original config's folder. The header names the file but not
/// where it lay, so the same config run from two folders gives the same dataset.
pub(crate) fn effective_config_toml(
    raw: &RawRun,
    source: &Path,
    overrides: &RunOverrides,
) -> Result<String, toml::ser::Error> {
    let body = toml::to_string(&content_table(raw)?)?;
    let name = source.file_name().map_or_else(
        || source.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let given = overrides.take_flags();
    Ok(format!(
        "# The effective config of this dataset: {name}{}, without [supervisor];\n# relative paths are relative to the folder {name} was in.\n\n{body}",
        if given.is_empty() {
            String::new()
        } else {
            format!(" with the command line's {} applied", given.join(", "))
        },
    ))
}

/// What a resume must find unchanged: the effective config without `[supervisor]` (how many
/// workers, which backend and how retries go do not change what is rendered) and without the
/// rig's path (the pipeline compares the rig itself, wherever its file lies).
pub(crate) fn resume_fingerprint(raw: &RawRun) -> Result<String, toml::ser::Error> {
    let mut r = raw.clone();
    if let Some(render) = r.render.as_mut() {
        render.rig = None;
    }
    toml::to_string(&content_table(&r)?)
}

/// [`resume_fingerprint`] without the output folder: what a run moved to another folder (a
/// campaign copied elsewhere, `<dir>.partial` renamed) must still find unchanged.
pub(crate) fn resume_fingerprint_anywhere(raw: &RawRun) -> Result<String, toml::ser::Error> {
    let mut r = raw.clone();
    r.output.dir = std::path::PathBuf::new();
    resume_fingerprint(&r)
}
