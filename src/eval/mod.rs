//! The paper's evaluation on this engine: the scenarios of Table 1 as crowd takes (`scenarios`),
//! their measures (`metrics`: per episode and per table row, paper S4.2), one table run over
//! every scenario × controller (`suite`), the suites that run Tables 1–3 and the speed table for
//! the trained policy, the sampling controller and a path-planning baseline on the same motion
//! model (`jobs`), their result files (`files`), `RESULTS.md` (`report`) and the paper's own
//! figures beside ours (`paper`); the `egogen policy` commands' jobs (`policy_commands`: the pose
//! prior fitted and checked, floor plans drawn, controllers over held-out episodes with their
//! walks drawn, on `policy_tasks`); the motion model measured (`motion_model`: `egogen motion
//! eval` and `control`). Uses `synth` to walk and `preview` to draw; `cli::eval_jobs` parses
//! `egogen eval`'s arguments and loads the shipped parts. `same_primitives_tests`: `egogen
//! policy eval`'s environment and a take's agent choose the same primitives; `planner_tests`:
//! the A* planner, the guide and the diversity measure on cases whose answers are known (tests
//! only).

pub(crate) mod files;
pub(crate) mod jobs;
pub(crate) mod metrics;
pub(crate) mod motion_model;
pub(crate) mod paper;
#[cfg(test)]
mod planner_tests;
pub(crate) mod policy_commands;
pub(crate) mod policy_tasks;
pub(crate) mod report;
#[cfg(test)]
mod same_primitives_tests;
pub(crate) mod scenarios;
pub(crate) mod suite;
