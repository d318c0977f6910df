//! How a campaign's takes are made: [`TakeMaker`] stages a take for the pool, finishes it when
//! its frames are rendered and lists its frames for the index. `StagedTakes` does it for
//! every real campaign with `egogen-run`'s own staging (motion, bodies' caches, shard specs)
//! and finishing (annotations, exports, manifest, stamp); a stand-in measures the pools and
//! the campaign's bookkeeping alone (`benches/campaign_farm.rs`).

use std::collections::HashMap;
use std::path::PathBuf;

use anyhow::Result;

use super::index::{take_rows, IndexRow};
use super::plan::TakeDef;
use crate::run_job::{prepare, RunRequest};
use crate::supervisor::{stage_take, PoolTake, Staged, StagedTake};

/// Makes a campaign's takes.
pub trait TakeMaker: Send {
    /// Stages `def`: its shards for the pool, or `None` when its folder is already complete.
    fn stage(&mut self, def: &TakeDef) -> Result<Option<PoolTake>>;
    /// Every frame of the staged take `id` is rendered: finishes it into its folder.
    fn finish(&mut self, id: &str) -> Result<()>;
    /// Forgets the staged take `id` (it failed).
    fn forget(&mut self, id: &str);
    /// The index rows of the complete take `def`.
    fn rows(&self, def: &TakeDef) -> Result<Vec<IndexRow>>;
}

/// `egogen-run`'s staging and finishing, take by take, into `<out>/takes/<id>/`.
pub(crate) struct StagedTakes {
    /// The campaign folder.
    pub out: PathBuf,
    /// The run config every take starts from.
    pub run: PathBuf,
    /// Blender and the backend, as the command line gave them.
    pub request: RunRequest,
    pub workers: Option<usize>,
    pub backend: Option<crate::plan::Backend>,
    staged: HashMap<String, Box<StagedTake>>,
}

impl StagedTakes {
    pub(crate) fn new(out: PathBuf, run: PathBuf, request: RunRequest) -> Self {
        StagedTakes {
            out,
            run,
            request,
            workers: None,
            backend: None,
            staged: HashMap::new(),
        }
    }
}

impl TakeMaker for StagedTakes {
    fn stage(&mut self, def: &TakeDef) -> Result<Option<PoolTake>> {
        let mut overrides = def.overrides(&self.out.join("takes"));
        overrides.workers = self.workers;
        overrides.backend = self.backend;
        let run = prepare(&self.run, &overrides, &self.request)?;
        let Some(render) = &run.plan.render else {
            anyhow::bail!("{} has no [render] section", self.run.display());
        };
        let motion = run.make_motion()?;
        let staged = stage_take(
            &run.plan,
            render,
            run.run_motion(&motion),
            &run.model,
            &self.run,
            &run.options,
            || Ok(()),
        )?;
        match staged {
            Staged::Complete(_) => Ok(None),
            Staged::Take(take) => {
                let dataset = take.dataset.clone();
                self.staged.insert(def.id.clone(), take);
                Ok(Some(PoolTake {
                    name: def.id.clone(),
                    shards: dataset.pending_shards(),
                    dataset,
                }))
            }
        }
    }

    fn finish(&mut self, id: &str) -> Result<()> {
        let staged = self
            .staged
            .remove(id)
            .ok_or_else(|| anyhow::anyhow!("take {id} was not staged here"))?;
        staged.finish()?;
        // Its checksums came from the frames' bytes in memory: a resume need not read it again.
        // Without a stamp (it could not be written) a resume verifies the take in full.
        if let Err(e) = super::stamp::write_stamp(&self.out, id, &staged.dir) {
            eprintln!(
                "egogen-run: campaign: take {id}: no stamp ({e:#}); a resume will verify it in full"
            );
        }
        Ok(())
    }

    fn forget(&mut self, id: &str) {
        self.staged.remove(id);
    }

    fn rows(&self, def: &TakeDef) -> Result<Vec<IndexRow>> {
        take_rows(def, &self.out.join("takes").join(&def.id), &self.out)
    }
}
