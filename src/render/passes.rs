//! Which images a run's frame files hold (`[render] passes`), and what each costs to make:
//! which of Blender's two renders it needs, which raw passes, which frame-file channels it
//! becomes. Only what is asked is rendered, assembled, validated and listed. Outputs made from
//! the frames (annotations, COLMAP) are `export`'s.

use serde::{Deserialize, Serialize};

/// One output a dataset can hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Pass {
    /// Colour with motion blur (`rgb.*`, or `gray.Y` for a monochrome camera).
    Colour,
    /// Planar depth (`depth.Z`).
    Depth,
    /// Surface normals in the camera frame (`normal.*`).
    Normals,
    /// Object and agent ids (`segmentation.id`), and a person's body part (`segmentation.part`).
    Segmentation,
    /// Surface points in the world frame (`position.*`).
    Position,
    /// Optical flow to the next and previous saved frame (`flow_forward.*`, `flow_backward.*`).
    Flow,
    /// Depth through a sensor noise model (`depth_noisy.Z`, cameras of `[render.depth_noise]`).
    DepthNoise,
}

impl Pass {
    /// Every pass, in config order.
    pub(crate) const ALL: [Pass; 7] = [
        Pass::Colour,
        Pass::Depth,
        Pass::Normals,
        Pass::Segmentation,
        Pass::Position,
        Pass::Flow,
        Pass::DepthNoise,
    ];

    /// Its name in a config.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Pass::Colour => "colour",
            Pass::Depth => "depth",
            Pass::Normals => "normals",
            Pass::Segmentation => "segmentation",
            Pass::Position => "position",
            Pass::Flow => "flow",
            Pass::DepthNoise => "depth_noise",
        }
    }

    /// The pass a config names, if any.
    pub(crate) fn from_name(name: &str) -> Option<Pass> {
        Pass::ALL.into_iter().find(|p| p.name() == name)
    }
}

/// The passes a run renders.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Passes(u16);

impl Default for Passes {
    /// Everything but depth noise (which needs `[render.depth_noise]`).
    fn default() -> Self {
        Passes::of(Pass::ALL.into_iter().filter(|&p| p != Pass::DepthNoise))
    }
}

impl Passes {
    pub(crate) const NONE: Passes = Passes(0);

    pub(crate) fn of(passes: impl IntoIterator<Item = Pass>) -> Self {
        Passes(passes.into_iter().fold(0, |m, p| m | 1 << p as u16))
    }

    pub(crate) fn has(self, pass: Pass) -> bool {
        self.0 & (1 << pass as u16) != 0
    }

    pub(crate) fn with(self, pass: Pass) -> Self {
        Passes(self.0 | 1 << pass as u16)
    }

    /// Whether Blender renders the blurred colour image.
    pub(crate) fn needs_colour_render(self) -> bool {
        self.has(Pass::Colour)
    }

    /// The raw passes of the unblurred ground-truth render, in Blender's view-layer names
    /// (`use_pass_<name>`); empty when no ground truth is asked for, and then that render is
    /// skipped. Depth is computed from the surface point; depth noise needs the point and
    /// the normal.
    pub(crate) fn ground_truth_render_passes(self) -> Vec<&'static str> {
        let mut out = Vec::new();
        if self.has(Pass::Depth) || self.has(Pass::Position) || self.has(Pass::DepthNoise) {
            out.push("position");
        }
        if self.has(Pass::Normals) || self.has(Pass::DepthNoise) {
            out.push("normal");
        }
        if self.has(Pass::Segmentation) {
            out.push("object_index");
        }
        if self.has(Pass::Flow) {
            out.push("vector");
        }
        out
    }

    /// The channels a frame file of a camera holds, sorted as EXR stores them: `monochrome`
    /// cameras store colour as `gray.Y`; `noisy_depth` whether the camera has a depth-noise
    /// model; `garments` whether people wear outfits (their garments beside the
    /// segmentation). `valid.V` is always there.
    pub(crate) fn frame_channels(
        self,
        monochrome: bool,
        noisy_depth: bool,
        garments: bool,
    ) -> Vec<&'static str> {
        let mut out = vec!["valid.V"];
        if self.has(Pass::Colour) {
            if monochrome {
                out.push("gray.Y");
            } else {
                out.extend(["rgb.A", "rgb.B", "rgb.G", "rgb.R"]);
            }
        }
        if self.has(Pass::Depth) {
            out.push("depth.Z");
        }
        if self.has(Pass::DepthNoise) && noisy_depth {
            out.push("depth_noisy.Z");
        }
        if self.has(Pass::Normals) {
            out.extend(["normal.X", "normal.Y", "normal.Z"]);
        }
        if self.has(Pass::Position) {
            out.extend(["position.X", "position.Y", "position.Z"]);
        }
        if self.has(Pass::Segmentation) {
            out.extend(["segmentation.id", "segmentation.part"]);
            if garments {
                out.push("segmentation.garment");
            }
        }
        if self.has(Pass::Flow) {
            out.extend([
                "flow_backward.X",
                "flow_backward.Y",
                "flow_forward.X",
                "flow_forward.Y",
            ]);
        }
        out.sort_unstable();
        out
    }
}

/// Groups of channels a frame file may hold: a file holds each group whole or not at all, and
/// `valid.V` always (how `verify` checks a file without the run's config). The body parts and
/// the garments are groups of their own: files written before them, and takes without
/// outfits, have the ids alone.
pub(crate) const CHANNEL_GROUPS: [&[&str]; 11] = [
    &["valid.V"],
    &["rgb.A", "rgb.B", "rgb.G", "rgb.R"],
    &["gray.Y"],
    &["depth.Z"],
    &["depth_noisy.Z"],
    &["normal.X", "normal.Y", "normal.Z"],
    &["position.X", "position.Y", "position.Z"],
    &["segmentation.id"],
    &["segmentation.part"],
    &["segmentation.garment"],
    &[
        "flow_backward.X",
        "flow_backward.Y",
        "flow_forward.X",
        "flow_forward.Y",
    ],
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_default_is_everything_but_noise() {
        for p in Pass::ALL {
            assert_eq!(Pass::from_name(p.name()), Some(p));
        }
        assert_eq!(Pass::from_name("rgb"), None);
        let d = Passes::default();
        assert!(Pass::ALL
            .into_iter()
            .all(|p| d.has(p) == (p != Pass::DepthNoise)));
    }

    #[test]
    fn depth_only_needs_one_raw_pass_and_no_colour() {
        let depth = Passes::of([Pass::Depth]);
        assert!(!depth.needs_colour_render());
        assert_eq!(depth.ground_truth_render_passes(), ["position"]);
        assert_eq!(
            depth.frame_channels(false, true, true),
            ["depth.Z", "valid.V"]
        );
        let colour = Passes::of([Pass::Colour]);
        assert!(colour.ground_truth_render_passes().is_empty());
        assert_eq!(
            colour.frame_channels(true, false, false),
            ["gray.Y", "valid.V"]
        );
        let ids = Passes::of([Pass::Segmentation]);
        assert_eq!(
            ids.frame_channels(false, false, false),
            ["segmentation.id", "segmentation.part", "valid.V"]
        );
        assert_eq!(
            ids.frame_channels(false, false, true),
            [
                "segmentation.garment",
                "segmentation.id",
                "segmentation.part",
                "valid.V"
            ]
        );
    }

    #[test]
    fn every_frame_channel_is_in_exactly_one_group() {
        let all = Passes::of(Pass::ALL);
        for mono in [false, true] {
            for ch in all.frame_channels(mono, true, true) {
                let n = CHANNEL_GROUPS.iter().filter(|g| g.contains(&ch)).count();
                assert_eq!(n, 1, "{ch}");
            }
        }
    }
}
