//! What the frame file's EXR compression costs, on a real frame: the frame re-encoded with
//! each lossless codec of the `exr` crate (ZIP16, egogen's; PIZ; RLE; none) — size, encode
//! time (one thread, as `FrameImage::encode`) and decode time (one thread, as the validation
//! read of every written frame), each checked lossless against the frame as read.
//!
//! `cargo bench --bench frame_codec -- FRAME.exr` (a frame file of any run, e.g. a full-size
//! Aria RGB frame: `resolution_scale = 1.0`). Without a frame it says so and measures nothing.

use exr::prelude::*;
use std::time::Instant;

fn read_all(bytes: &[u8]) -> FlatImage {
    read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .non_parallel()
        .from_buffered(std::io::Cursor::new(bytes))
        .expect("an EXR frame file")
}

fn main() {
    let Some(path) = std::env::args().skip(1).find(|a| a.ends_with(".exr")) else {
        eprintln!("frame_codec: give a frame file: cargo bench --bench frame_codec -- FRAME.exr");
        return;
    };
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("reading {path}: {e}"));
    let frame = read_all(&bytes);
    println!("{path}: {:.1} MB as written\n", bytes.len() as f64 / 1e6);
    println!("| codec | MB | encode s | decode s | lossless |");
    println!("|---|---|---|---|---|");
    for (name, encoding) in [
        ("ZIP16 (egogen's)", Encoding::SMALL_LOSSLESS),
        ("PIZ", Encoding::SMALL_FAST_LOSSLESS),
        ("RLE", Encoding::FAST_LOSSLESS),
        ("none", Encoding::UNCOMPRESSED),
    ] {
        let mut image = frame.clone();
        for layer in image.layer_data.iter_mut() {
            layer.encoding = encoding;
        }
        let t = Instant::now();
        let mut out = std::io::Cursor::new(Vec::new());
        image
            .write()
            .non_parallel()
            .to_buffered(&mut out)
            .expect("encoding");
        let encode_s = t.elapsed().as_secs_f64();
        let out = out.into_inner();
        let t = Instant::now();
        let back = read_all(&out);
        let decode_s = t.elapsed().as_secs_f64();
        let lossless = back.layer_data.iter().zip(&frame.layer_data).all(|(a, b)| {
            a.channel_data
                .list
                .iter()
                .zip(&b.channel_data.list)
                .all(|(x, y)| x.sample_data == y.sample_data)
        });
        println!(
            "| {name} | {:.1} | {encode_s:.2} | {decode_s:.2} | {lossless} |",
            out.len() as f64 / 1e6
        );
    }
}
