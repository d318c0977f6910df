#!/usr/bin/env bash
# Do two egogen binaries make the same takes and evaluations? For refactors that must not change
# behaviour: runs both on the same synth configs (crowd4 with each controller, 8 s; the apartment
# with activities, 3 people × 20 s; the small house with sits and pick-ups, 5 people × 40 s) and
# the same `egogen policy eval` runs (sampling in mixed scenes, the guided policy on memory in
# floor plans, the policy seeing crossing people ahead, the policy in the apartment), then
# compares every file byte for byte (summaries and reports without their wall-clock times).
#
#   tools/refactor_identity.sh OLD_EGOGEN NEW_EGOGEN OUT_DIR
#
# Exit status 0 when everything is identical; the differing files are listed otherwise.
set -euo pipefail
if [ $# -ne 3 ]; then
    echo "usage: $0 OLD_EGOGEN NEW_EGOGEN OUT_DIR (a new folder)" >&2
    exit 2
fi
OLD=$(realpath "$1"); NEW=$(realpath "$2"); OUT=$3
if [ -e "$OUT" ]; then echo "$OUT exists; give a new folder" >&2; exit 2; fi
ROOT=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$OUT"; OUT=$(realpath "$OUT")

make_configs() { # $1: folder of this side
    local d=$1; mkdir -p "$d/cfg"
    for v in policy policy_mean sampling path_follow; do
        k=""; case $v in sampling|path_follow) k="k = 8";; esac
        sed -e "s#^steering = .*#steering = \"$v\"\n$k#" -e "s#\.\./out/crowd4#$d/crowd4_$v#" \
            -e 's#^duration_s = .*#duration_s = 8.0#' "$ROOT/configs/crowd4.toml" > "$d/cfg/crowd4_$v.toml"
    done
    sed -e "s#dir = .*#dir = \"$d/acts\"#" -e 's#^duration_s = .*#duration_s = 20.0#' \
        -e "s#\"\.\./#\"$ROOT/#g" "$ROOT/configs/apartment_activities.toml" > "$d/cfg/acts.toml"
    sed -e "s#apartment.glb#small_house.glb#" \
        -e 's#^weights = .*#weights = { walk = 0.2, stand = 1.0, sit = 4.0, pick_up = 2.0 }#' \
        -e 's#^duration_s = .*#duration_s = 40.0#' -e 's#^count = 3#count = 5#' \
        -e "s#dir = .*#dir = \"$d/skips\"#" "$d/cfg/acts.toml" > "$d/cfg/skips.toml"
}

run_side() { # $1: binary, $2: folder
    local bin=$1 d=$2 p="$ROOT/assets/policy/scene_weights/policy.safetensors"
    make_configs "$d"
    for f in "$d"/cfg/*.toml; do
        (cd "$ROOT/configs" && "$bin" synth --quiet "$f") > "$d/$(basename "$f" .toml).log" 2>&1
    done
    mkdir -p "$d/eval"
    "$bin" policy eval --k 4 --episodes 16 --envs 8 --rooms-share 0.5 --crossing-share 0.3 > "$d/eval/sampling.json"
    "$bin" policy eval --k 2 --policy "$p" --episodes 16 --envs 8 --rooms-share 1 --guide-lookahead-m 1 \
        --guide-memory --guide-unknown-cost 0.5 --max-primitives 13 --success-m 0.2 > "$d/eval/guided.json"
    "$bin" policy eval --policy "$p" --mean-action --episodes 16 --envs 8 --crossing-share 1 \
        --crossing-people 2 --people-seen-ahead > "$d/eval/ahead.json"
    "$bin" policy eval --policy "$p" --episodes 8 --envs 8 --scene "$ROOT/assets/scenes/apartment.glb" > "$d/eval/apartment.json"
}

echo "old: $OLD"; run_side "$OLD" "$OUT/old"
echo "new: $NEW"; run_side "$NEW" "$OUT/new"

python3 - "$OUT/old" "$OUT/new" <<'PY'
import hashlib, json, pathlib, sys
old, new = map(pathlib.Path, sys.argv[1:])
TIMES = {"wall_s", "agent_seconds_per_wall_s", "config"}
def scrub(x):
    if isinstance(x, dict):
        return {k: scrub(v) for k, v in x.items() if k not in TIMES}
    if isinstance(x, list):
        return [scrub(v) for v in x]
    return x
def content(p):
    if p.name in ("summary.json",):
        return json.dumps(scrub(json.loads(p.read_text())), sort_keys=True).encode()
    if p.suffix == ".json" and p.parent.name == "eval":
        return "\n".join(json.dumps(scrub(json.loads(l)), sort_keys=True) for l in p.read_text().splitlines()).encode()
    return p.read_bytes()
skip = lambda p: p.suffix == ".log" or p.name == "manifest.json" or "cfg" in p.parts
files = sorted(p.relative_to(old) for p in old.rglob("*") if p.is_file() and not skip(p))
differ = [str(f) for f in files if not (new / f).is_file() or content(old / f) != content(new / f)]
print(f"{len(files)} files compared, {len(differ)} differ")
for f in differ:
    print("  differs:", f)
sys.exit(1 if differ else 0)
PY
