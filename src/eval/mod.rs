//! The paper's evaluation on this engine (issue: Tables 1–3): the scenarios of Table 1 as crowd
//! takes, their measures (paper S4.2) and the tables, for the trained policy, the sampling
//! controller and a path-planning baseline on the same motion model. Uses `synth` to walk and
//! `preview` to draw; writes nothing itself (the `egogen eval` command does).

pub mod files;
pub mod metrics;
pub mod paper;
pub mod report;
pub mod scenarios;
pub mod suite;
