//! Why an activity is not played where it was drawn: each reason typed, its words the
//! skipped activity's `reason` in summaries and annotations.

use crate::body::PoseError;

/// What the body was doing when it would have entered the scene or left the floor.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Doing {
    /// Standing where the walk ended.
    StandingThere,
    /// Bending to the floor where the walk ended.
    BendingThere,
    /// Sitting on the seat of the object named.
    SittingOn(String),
    /// Bending to take the scene thing named.
    Taking(String),
}

impl std::fmt::Display for Doing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Doing::StandingThere => f.write_str("standing there"),
            Doing::BendingThere => f.write_str("bending there"),
            Doing::SittingOn(seat) => write!(f, "sitting on {seat}"),
            Doing::Taking(thing) => write!(f, "bending to take {thing}"),
        }
    }
}

/// Why an activity cannot be played where it was drawn.
#[derive(Debug, thiserror::Error)]
pub(crate) enum Refusal {
    #[error("{doing}, the body would enter the scene {depth_m:.2} m at its frame {frame}")]
    EntersScene {
        doing: Doing,
        depth_m: f64,
        frame: usize,
    },
    #[error("{doing}, the pelvis would leave the walkable floor at its frame {frame}")]
    LeavesFloor { doing: Doing, frame: usize },
    #[error(
        "no sit clip comes within activities.seat_fit_m = {fit_m} m of the {height_m:.2} m seat \
         of {seat} (nearest: {nearest} at {nearest_m:.2} m)"
    )]
    NoClipFits {
        fit_m: f64,
        height_m: f64,
        seat: String,
        nearest: String,
        nearest_m: f64,
    },
    #[error(
        "standing in front of the seat of {seat}, the body would stand over furniture (the clip \
         stands {in_front_m:.2} m in front of where it sits)"
    )]
    StandsOverFurniture { seat: String, in_front_m: f64 },
    #[error("the place in front of the seat of {seat} was not reached")]
    SeatNotReached { seat: String },
    #[error("the place beside {thing} was not reached")]
    ThingNotReached { thing: String },
    #[error("the scene has no seat (`egogen scene inspect` lists them)")]
    NoSeat,
    #[error("every seat on this floor is taken")]
    SeatsTaken,
    #[error("every free seat on this floor was walked to before and not reached")]
    SeatsUnreached,
    #[error("the take ended before it began")]
    TakeEnded,
    #[error("`{0}` is not played where a walk ended")]
    NotHere(&'static str),
    #[error("no sit clip")]
    NoSitClip,
    #[error("the activity clip {0} is not loaded")]
    NoClip(&'static str),
    #[error(transparent)]
    Pose(#[from] PoseError),
}
