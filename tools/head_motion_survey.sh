#!/usr/bin/env bash
# How heads move in egogen's takes against real heads (docs/MOTION.md, "Head motion"): six 60 s
# takes with activities in the shipped dwellings (apartment seeds 0 and 1, small house seeds 0
# and 1, stepped house, TurtleBot3 house; 3 people each) and the default take (10 s, walking),
# each made twice: as shipped and with `[walker] smooth_joins = false, steady_head = false` (the
# primitives as decoded); then `egogen motion head-stats` over every person of every take, the
# 83 CMU locomotion clips the motion model learnt from and the real Aria wearer's MPS
# trajectory. Writes OUT/<variant>/<take>/ (the takes), OUT/stats.json and prints the tables.
# Usage: tools/head_motion_survey.sh OUT [EGOGEN_BIN]   (OUT must not exist; 2 min here)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:?usage: tools/head_motion_survey.sh OUT [EGOGEN_BIN]}"
bin="${2:-$root/target/release/egogen}"
if [ -e "$out" ]; then echo "$out already exists; not overwriting it" >&2; exit 1; fi
if [ ! -x "$bin" ]; then echo "$bin: no egogen binary (cargo build --release --locked)" >&2; exit 1; fi
mkdir -p "$out/configs"
takes=(apartment:0 apartment:1 small_house:0 small_house:1 stepped_house:0 turtlebot3_house:0)
make_config() { # name scene_config seed variant duration activities
    local name="$1" src="$2" seed="$3" variant="$4" duration="$5" activities="$6"
    local cfg="$out/configs/${variant}_${name}.toml"
    {
        grep -v '^\[output\]' "$root/configs/$src" | grep -v '^dir = ' \
            | sed -e "s#^path = \"\.\./#path = \"$root/#" \
                  -e "s#^duration_s = .*#duration_s = $duration#" \
                  -e "s#^seed = .*#seed = $seed#" \
                  -e '/^\[walker\]/,/^\[/{/^\[walker\]/d;/^success_m/d;/^max_primitives/d}'
        if [ "$activities" = yes ]; then
            printf '\n[activities]\nweights = { walk = 1.0, stand = 1.0, sit = 2.0, pick_up = 1.0 }\nstand_s = [3.0, 8.0]\nsit_s = [4.0, 12.0]\n'
        fi
        if [ "$variant" = decoded ]; then
            printf '\n[walker]\nsmooth_joins = false\nsteady_head = false\n'
        fi
        printf '\n[output]\ndir = "%s"\n' "$out/$variant/$name"
    } > "$cfg"
    echo "$cfg"
}
for variant in decoded shipped; do
    mkdir -p "$out/$variant"
    for t in "${takes[@]}"; do
        scene="${t%%:*}"; seed="${t##*:}"
        src="${scene}3.toml"; [ "$scene" = apartment ] && src=apartment3.toml
        "$bin" synth --quiet "$(make_config "${scene}_s$seed" "$src" "$seed" "$variant" 60.0 yes)" >/dev/null
    done
    "$bin" synth --quiet "$(make_config default apartment3.toml 0 "$variant" 10.0 no)" >/dev/null
done
sources=()
for variant in decoded shipped; do
    for d in "$out/$variant"/*/; do sources+=("${d%/}"); done
done
"$bin" motion head-stats "${sources[@]}" "$root/assets/motion/cmu" \
    "$root/assets/reference/aria_mps_sample_closed_loop_trajectory.csv" \
    --json "$out/stats.json" > /dev/null 2> "$out/table.txt"
python3 "$root/tools/head_motion_summary.py" "$out/stats.json"
