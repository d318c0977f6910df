//! `egogen inspect`: real EXR files written by the `exr` crate in Blender's two layouts (4.5:
//! one part, dotted channel names; 5.0: one part per pass) read back with the right channels,
//! statistics and previews.

mod common;

use std::path::Path;
use std::process::Command;

use egogen::inspect::preview::{colormap, palette, preview_kind, PreviewKind};
use egogen::inspect::{pass_preview, ExrContents};
use exr::prelude::*;

const W: usize = 16;
const H: usize = 8;

fn depth(x: usize, _y: usize) -> f32 {
    if x == 15 {
        1e10 // background
    } else {
        1.0 + x as f32 * 0.5
    }
}

/// Blender 4.5 layout: one part, channels `ViewLayer.<Pass>.<C>`.
fn write_single_part(path: &Path) {
    let mut chans: Vec<AnyChannel<FlatSamples>> = Vec::new();
    let f = |g: &dyn Fn(usize, usize) -> f32| {
        FlatSamples::F32((0..W * H).map(|i| g(i % W, i / W)).collect())
    };
    let mut push = |name: &str, s: FlatSamples| chans.push(AnyChannel::new(name, s));
    push("ViewLayer.Combined.R", f(&|x, _| x as f32 / 15.0));
    push("ViewLayer.Combined.G", f(&|_, _| 0.5));
    push(
        "ViewLayer.Combined.B",
        f(&|_, y| if y == 0 { f32::NAN } else { 0.0 }),
    );
    push("ViewLayer.Depth.Z", f(&depth));
    push("ViewLayer.Normal.X", f(&|_, _| 0.0));
    push("ViewLayer.Normal.Y", f(&|_, _| 0.0));
    push("ViewLayer.Normal.Z", f(&|_, _| 1.0));
    push("ViewLayer.IndexOB.X", f(&|x, _| (x / 4) as f32));
    chans.sort_by(|a, b| a.name.cmp(&b.name));
    let layer = Layer::new(
        (W, H),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(chans.into()),
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
}

/// Blender 5.0 layout: one part per pass.
fn write_multi_part(path: &Path) {
    let rgb = Layer::new(
        (W, H),
        LayerAttributes::named("ViewLayer.Combined"),
        Encoding::FAST_LOSSLESS,
        SpecificChannels::rgb(|p: Vec2<usize>| (p.0 as f32 / 15.0, 0.5f32, 0.0f32)),
    );
    let z = Layer::new(
        (W, H),
        LayerAttributes::named("ViewLayer.Depth"),
        Encoding::FAST_LOSSLESS,
        SpecificChannels::build()
            .with_channel("Z")
            .with_pixel_fn(|p: Vec2<usize>| (depth(p.0, p.1),)),
    );
    let flow = Layer::new(
        (W, H),
        LayerAttributes::named("ViewLayer.Vector"),
        Encoding::FAST_LOSSLESS,
        SpecificChannels::build()
            .with_channel("X")
            .with_channel("Y")
            .with_pixel_fn(|_p: Vec2<usize>| (2.0f32, 0.0f32)),
    );
    Image::empty(ImageAttributes::new(IntegerBounds::from_dimensions((W, H))))
        .with_layer(rgb)
        .with_layer(z)
        .with_layer(flow)
        .write()
        .to_file(path)
        .unwrap();
}

#[test]
fn single_part_blender_45_layout() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("frame_0001.exr");
    write_single_part(&path);
    let c = ExrContents::read(&path).unwrap();
    assert_eq!(c.parts, 1);
    let names: Vec<&str> = c.passes.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "ViewLayer.Combined",
            "ViewLayer.Depth",
            "ViewLayer.IndexOB",
            "ViewLayer.Normal"
        ]
    );
    let b = c.channel("ViewLayer.Combined.B").unwrap().stats();
    assert_eq!(b.nan, W);
    let z = c.channel("ViewLayer.Depth.Z").unwrap().stats();
    assert_eq!((z.min, z.max), (1.0, 1e10));
    let kinds: Vec<PreviewKind> = c.passes.iter().map(|p| preview_kind(&c, p)).collect();
    assert_eq!(
        kinds,
        [
            PreviewKind::Colour,
            PreviewKind::Depth,
            PreviewKind::Ids,
            PreviewKind::Normal
        ]
    );
    // Depth: nearest column gets the map's start, the background stays black.
    let d = pass_preview(&c, &c.passes[1]);
    assert_eq!(d.pixels[0], colormap(0.0));
    assert_eq!(d.pixels[14], colormap(1.0));
    assert_eq!(d.pixels[15], [0, 0, 0]);
    // Ids: one palette colour per object, 0 black.
    let ids = pass_preview(&c, &c.passes[2]);
    assert_eq!(ids.pixels[0], [0, 0, 0]);
    assert_eq!(ids.pixels[5], palette(1.0));
    assert_ne!(palette(1.0), palette(2.0));
    // Normals facing the camera (+z) are (128, 128, 255).
    assert_eq!(pass_preview(&c, &c.passes[3]).pixels[3], [128, 128, 255]);
}

#[test]
fn multi_part_blender_50_layout_and_cli() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("frame_0002.exr");
    write_multi_part(&path);
    let c = ExrContents::read(&path).unwrap();
    assert_eq!(c.parts, 3);
    assert!(c.channel("ViewLayer.Depth.Z").is_some());
    let flow = c
        .passes
        .iter()
        .find(|p| p.name == "ViewLayer.Vector")
        .unwrap();
    assert_eq!(preview_kind(&c, flow), PreviewKind::Flow);
    // Flow (2, 0): hue 0 (red) at full brightness.
    assert_eq!(pass_preview(&c, flow).pixels[0], [255, 0, 0]);

    let png = dir.path().join("sheet.png");
    let out = Command::new(env!("CARGO_BIN_EXE_egogen"))
        .arg("inspect")
        .arg(&path)
        .arg("--preview")
        .arg(&png)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("3 part(s)") && text.contains("ViewLayer.Depth") && text.contains("NaN 0"),
        "{text}"
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let info = decoder.read_info().unwrap().info().clone();
    assert_eq!(
        (info.width as usize, info.height as usize),
        (3 * W + 2 * 8, H)
    );
    // Refuses to overwrite, and a non-EXR file is named in the error.
    let again = Command::new(env!("CARGO_BIN_EXE_egogen"))
        .arg("inspect")
        .arg(&path)
        .arg("--preview")
        .arg(&png)
        .output()
        .unwrap();
    assert!(!again.status.success());
    let bad = dir.path().join("not.exr");
    std::fs::write(&bad, "nope").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_egogen"))
        .arg("inspect")
        .arg(&bad)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("not.exr"));
}

/// Several files, one pass each (`--pass`), side by side; auto exposure brings a uniform image
/// to middle grey; a missing pass names the passes the file has.
#[test]
fn several_files_one_pass_and_auto_exposure() {
    use egogen::inspect::preview::{auto_exposure, pass_preview_exposed, AUTO_EXPOSURE_KEY};
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.exr");
    let b = dir.path().join("b.exr");
    write_single_part(&a);
    write_multi_part(&b);
    // A uniform grey of luminance 4 is scaled to the key; sRGB(0.18) is 118.
    let grey = dir.path().join("grey.exr");
    let plane = |v: f32| FlatSamples::F32(vec![v; W * H]);
    let layer = Layer::new(
        (W, H),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(
            vec![
                AnyChannel::new("rgb.R", plane(4.0)),
                AnyChannel::new("rgb.G", plane(4.0)),
                AnyChannel::new("rgb.B", plane(4.0)),
            ]
            .into(),
        ),
    );
    Image::from_layer(layer).write().to_file(&grey).unwrap();
    let c = ExrContents::read(&grey).unwrap();
    let scale = auto_exposure(&c, &c.passes[0]);
    assert!((scale * 4.0 - AUTO_EXPOSURE_KEY).abs() < 1e-4, "{scale}");
    assert_eq!(
        pass_preview_exposed(&c, &c.passes[0], scale).pixels[0],
        [118; 3]
    );

    let png = dir.path().join("two.png");
    let out = Command::new(env!("CARGO_BIN_EXE_egogen"))
        .arg("inspect")
        .args([&a, &grey])
        .args(["--exposure", "auto", "--pass", "ViewLayer.Depth"])
        .arg("--preview")
        .arg(&png)
        .output()
        .unwrap();
    // grey.exr has no depth pass: named with what it has.
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("grey.exr")
            && err.contains("no pass `ViewLayer.Depth`")
            && err.contains("rgb"),
        "{err}"
    );
    common::succeeds(
        Command::new(env!("CARGO_BIN_EXE_egogen"))
            .arg("inspect")
            .args([&a, &b])
            .args(["--pass", "ViewLayer.Depth", "--preview"])
            .arg(&png),
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let info = decoder.read_info().unwrap().info().clone();
    assert_eq!((info.width as usize, info.height as usize), (2 * W + 8, H));
}
