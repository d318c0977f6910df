#!/usr/bin/env bash
# Builds the redistributable motion training clips in assets/motion/ from real mocap, retargeted
# onto the shipped body model and resampled to 40 fps by `egogen motion import`:
#   - CMU trials 01_01 and 01_03 (BVH, 120 fps) from Debian's assimp-testmodels;
#   - DeepMimic humanoid3d clips (30 fps) from PyPI pybullet 3.2.7 (pybullet_data/data/motions);
#   - the 83 CMU locomotion clips (BVH, 120 fps) in assets/mocap/cmu_locomotion.tar.xz (its
#     README.md and MANIFEST.csv give provenance and terms), into assets/motion/cmu/;
#   - the 6 CMU activity clips (sit down and stand up at three seat heights, lift, pick up; BVH,
#     30 fps) in assets/mocap/cmu_activities/ (its README.md and MANIFEST.csv), into
#     assets/motion/activities/ (not training data: played by takes' activities, docs/ACTIVITIES.md).
# Mirrored copies are made at training time (egogen::motion::resample::mirror), not stored.
#
#   bash tools/build_training_clips.sh        # needs root for apt-get (or the package installed)
#   bash tools/build_training_clips.sh cmu    # only the CMU locomotion clips (no download)
#   bash tools/build_training_clips.sh activities  # only the CMU activity clips (no download)
# EGOGEN_BIN=path/to/egogen uses that binary instead of building a release one.
set -euo pipefail
cd "$(dirname "$0")/.."
only=${1:-all}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ -z "${EGOGEN_BIN:-}" ]; then
  cargo build --release --locked --bin egogen
  EGOGEN_BIN=./target/release/egogen
fi
mkdir -p assets/motion
import() { # source output [extra args]
  local src=$1 name=$2; shift 2
  rm -f "assets/motion/$name.npz"
  "$EGOGEN_BIN" motion import "$src" --out "assets/motion/$name.npz" --rate-hz 40 "$@"
}
# CMU activities: frame 0 of every file is the cgspeed T-pose calibration frame.
if [ "$only" = all ] || [ "$only" = activities ]; then
  mkdir -p assets/motion/activities
  for bvh in assets/mocap/cmu_activities/*.bvh; do
    trial=$(basename "$bvh" .bvh)
    rm -f "docs/mocap_cmu_$trial.png"
    strip=()
    if [ "$trial" = 75_18 ] || [ "$trial" = 64_28 ]; then strip=(--strip "docs/mocap_cmu_$trial.png"); fi
    import "$bvh" "activities/$trial" --skip-frames 1 "${strip[@]}"
  done
fi
if [ "$only" = activities ]; then exit 0; fi
# CMU locomotion: every clip's frame 0 is a T-pose calibration frame except 16_11's (a re-saved
# copy of the trial without it).
tar -xJf assets/mocap/cmu_locomotion.tar.xz -C "$tmp"
mkdir -p assets/motion/cmu
for bvh in "$tmp"/cmu/*.bvh; do
  trial=$(basename "$bvh" .bvh)
  skip=1
  if [ "$trial" = 16_11 ]; then skip=0; fi
  import "$bvh" "cmu/$trial" --skip-frames "$skip"
done
if [ "$only" = cmu ]; then exit 0; fi
BVH=/usr/share/assimp/models/BVH
if [ ! -f "$BVH/01_01.bvh" ]; then
  apt-get update -qq && apt-get install -y -qq assimp-testmodels
fi
python3 -m pip download -q --no-deps -d "$tmp" pybullet==3.2.7
python3 - "$tmp" <<'PY'
import glob, sys, zipfile
tmp = sys.argv[1]
with zipfile.ZipFile(glob.glob(f"{tmp}/pybullet-*.whl")[0]) as z:
    for n in z.namelist():
        if n.startswith("pybullet_data/data/motions/") and n.endswith(".txt"):
            z.extract(n, tmp)
PY
MOT="$tmp/pybullet_data/data/motions"
rm -f docs/mocap_cmu_01_01.png docs/mocap_cmu_01_03.png
# Source frame 0 of the cgspeed CMU files is a T-pose calibration frame: skip it.
import "$BVH/01_01.bvh" cmu_01_01 --skip-frames 1 --strip docs/mocap_cmu_01_01.png
import "$BVH/01_03.bvh" cmu_01_03 --skip-frames 1 --strip docs/mocap_cmu_01_03.png
import "$MOT/humanoid3d_walk.txt" deepmimic_walk
import "$MOT/humanoid3d_run.txt" deepmimic_run
for clip in 0walk_forward turn_left0 turn_left1 turn_right0 turn_right1; do
  import "$MOT/walker/$clip.txt" "deepmimic_walker_$clip"
done
