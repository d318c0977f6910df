//! Synth: motion + body → per-frame posed bodies and eye-anchor (CPF) trajectories, and the
//! folders they are written to: crowds of agents steered through a scene, their motion
//! finished as written (joins smoothed, head steadied: `motion::joins`, `motion::head_stabilise`)
//! (`crowd`), what they do besides walking (`activity`: the schema, one file per activity —
//! standing and looking around, sitting, picking up — and why one is skipped), the objects
//! picked up and carried (`held_object`), placing a motion
//! in a scene (`placement`), a take of agents from its plan (`take`), a body posed over a
//! sequence with its CPF and hand landmarks per frame (`body_track`), the penetration tests
//! (`penetration`), the folder of one sequence (`sequence_dir`) and of a crowd take
//! (`crowd_dir`), and the body caches Blender plays (`body_cache`). Two commands' jobs that draw
//! bodies, motion and what a walker senses with `preview`, which `body`, `motion` and `scene`
//! may not use, are here too: `body_pictures` (`egogen body shapes|preview|hands`, `egogen
//! motion import --strip`) and `scene_inspect` (`egogen scene inspect`).

pub(crate) mod activity;
pub(crate) mod body_cache;
pub(crate) mod body_pictures;
pub(crate) mod body_track;
pub mod crowd;
pub(crate) mod crowd_dir;
pub(crate) mod held_object;
pub(crate) mod penetration;
pub(crate) mod placement;
pub(crate) mod scene_inspect;
pub mod sequence_dir;
pub mod take;

pub(crate) use body_track::{track_body, BodyTrack, TrackFrame};
pub(crate) use sequence_dir::{pose_meshes, write_sequence_dir};
