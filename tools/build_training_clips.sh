#!/usr/bin/env bash
# Builds the redistributable motion training clips in assets/motion/ from real mocap:
# CMU trials 01_01 and 01_03 (BVH, 120 fps) from Debian's assimp-testmodels, retargeted onto
# the shipped body model and resampled to 40 fps by `egogen motion import-bvh`.
# Mirrored copies are made at training time (egogen::motion::resample::mirror), not stored.
#
#   bash tools/build_training_clips.sh        # needs root for apt-get (or the package installed)
set -euo pipefail
cd "$(dirname "$0")/.."
BVH=/usr/share/assimp/models/BVH
if [ ! -f "$BVH/01_01.bvh" ]; then
  apt-get update -qq && apt-get install -y -qq assimp-testmodels
fi
cargo build --release --locked --bin egogen
mkdir -p assets/motion
for trial in 01_01 01_03; do
  out=assets/motion/cmu_${trial}.npz
  rm -f "$out" "docs/mocap_cmu_${trial}.png"
  # Source frame 0 of the cgspeed CMU files is a T-pose calibration frame: skip it.
  ./target/release/egogen motion import-bvh "$BVH/${trial}.bvh" --out "$out" --rate-hz 40 \
    --skip-frames 1 --strip "docs/mocap_cmu_${trial}.png"
done
