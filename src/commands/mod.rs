//! The binaries' command lines, the top of the layering: `egogen` (`egogen`: body models,
//! motion, policy, scenes, exports, previews) and `egogen-run` (`egogen_run`: a run config or
//! a campaign to a dataset, and `verify`). Each parses its arguments with clap and calls the
//! job; `src/bin/` holds two `main`s that call these.

pub mod egogen;
pub mod egogen_run;
