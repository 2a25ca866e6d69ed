#!/usr/bin/env bash
# Regression check for refactors: runs a fixed set of commands with one cablevib binary and
# writes every result that must not change (JSON, CSV, SVG) into a directory, with timing
# fields removed. Run it once with the binary before the change and once after, then diff:
#
#   scripts/compare-results.sh OLD_BINARY /tmp/before
#   scripts/compare-results.sh target/release/cablevib /tmp/after
#   diff -r /tmp/before /tmp/after && echo identical
#
# Or, to build the commit REV in a temporary worktree and compare it with the working tree:
#
#   scripts/compare-results.sh --against REV
#
# Needs python3 (standard library only) to strip timing fields.
set -euo pipefail

strip_json() { # drop timing keys (…_ns, …_seconds, ratios of times) from one JSON object
  python3 -c '
import json, sys
d = json.load(sys.stdin)
timing = lambda k: k.endswith("_ns") or k.endswith("_seconds") or k.endswith("_ratio") or k.endswith("_us") or k.endswith("_s")
def walk(x):
    if isinstance(x, dict):
        return {k: walk(v) for k, v in x.items() if not timing(k)}
    if isinstance(x, list):
        return [walk(v) for v in x]
    return x
json.dump(walk(d), sys.stdout, indent=1, sort_keys=True)
print()'
}

strip_csv() { # drop timing columns (…_ns) from a CSV file, keeping `#` lines
  python3 -c '
import csv, sys
lines = open(sys.argv[1]).read().splitlines()
comments = [l for l in lines if l.startswith("#")]
rows = list(csv.reader(l for l in lines if not l.startswith("#")))
keep = [i for i, c in enumerate(rows[0]) if not (c.endswith("_ns") or c.endswith("_seconds"))] if rows else []
for l in comments:
    print(l)
w = csv.writer(sys.stdout, lineterminator="\n")
for r in rows:
    w.writerow([r[i] for i in keep if i < len(r)])
' "$1"
}

run_all() {
  local bin=$1 out=$2
  mkdir -p "$out"
  local a="$out/analyze" w="$out/work"
  mkdir -p "$a" "$w"
  for scene in spatial-paper planar-paper; do
    for el in fem catenary continuous; do
      for n in 10 40; do
        "$bin" analyze $scene --element $el --elements $n --json | strip_json > "$a/$scene-$el-$n.json"
        "$bin" analyze $scene --element $el --elements $n --realtime --json | strip_json > "$a/$scene-$el-$n-rt.json"
      done
    done
    "$bin" analyze $scene --element massless --json | strip_json > "$a/$scene-massless.json"
    "$bin" analyze $scene --element auto --json | strip_json > "$a/$scene-auto.json"
    "$bin" analyze $scene --modes 10 | sed -E "s/dense solve [0-9.]+ ms/dense solve (time)/" > "$a/$scene-table.txt"
  done
  "$bin" analyze scenes/box_6dof.toml --json | strip_json > "$a/box-6dof.json"
  "$bin" analyze scenes/box_6dof.toml --realtime --json | strip_json > "$a/box-6dof-rt.json"
  "$bin" analyze spatial-paper --position 0.3,0.2,1.0 --t-min 30 --json | strip_json > "$a/spatial-offcentre.json"

  local b="$out/bench"; mkdir -p "$b"
  for model in "--element fem --elements 10" "--element fem --elements 40" "--element catenary --elements 10" \
               "--element continuous" "--element massless"; do
    local tag; tag=$(echo "$model" | tr -d ' -' )
    "$bin" bench spatial-paper $model --cycles 3000 --dense-samples 2 --json | strip_json > "$b/spatial-$tag.json"
    "$bin" bench planar-paper $model --cycles 3000 --dense-samples 2 --json | strip_json > "$b/planar-$tag.json"
  done
  "$bin" bench scenes/box_6dof.toml --cycles 2000 --dense-samples 1 --json | strip_json > "$b/box.json"

  local s="$out/sweeps"; mkdir -p "$s"
  "$bin" map spatial-paper --step 0.25 --z 1.0 --out "$s/map-spatial" --quiet > "$s/map-spatial.txt"
  "$bin" map planar-paper --step 0.1 --t-min 20 --value ee-mode --out "$s/map-planar" --quiet > "$s/map-planar.txt"
  "$bin" map spatial-paper --step 0.5 --x -0.5,0.5 --y -0.5,0.5 --z 0.5,1.5 --out "$s/map-3d" --quiet > "$s/map-3d.txt"
  "$bin" trajectory planar-paper --t-mins 10,20,40 --out "$s/traj-planar" --quiet > "$s/traj-planar.txt"
  "$bin" trajectory spatial-paper --element continuous --out "$s/traj-spatial" --quiet > "$s/traj-spatial.txt"
  printf 't,x,y,z\n0,0,0,1.25\n0.001,0.1,0,1.2\n# comment\n0.002,0.2,0.1,1.1\n' > "$w/traj.csv"
  "$bin" trajectory spatial-paper --csv "$w/traj.csv" --out "$s/traj-csv" --quiet > "$s/traj-csv.txt"
  "$bin" sweep-tmin spatial-paper --steps 9 --out "$s/tmin-spatial" > "$s/tmin-spatial.txt"
  "$bin" sweep-tmin planar-paper --from 10 --to 40 --compare 10:4.0,20:5.6 --out "$s/tmin-planar" > "$s/tmin-planar.txt"
  for scene in spatial-paper planar-paper; do
    "$bin" accuracy $scene --out-dir "$w/acc" --max-elements 12 --cycles 200 --rounds 1 --dense-max 6 > /dev/null
  done
  mkdir -p "$s/accuracy"
  for f in "$w"/acc/data/*.csv; do strip_csv "$f" > "$s/accuracy/$(basename "$f")"; done
  cp "$w"/acc/img/*error-vs-n.svg "$w"/acc/img/*mode3.svg "$s/accuracy/"
  rm -rf "$w"
  # output paths and wall times printed by the commands
  sed -i -E "s#$out#OUT#g; s/ in [0-9.]+ s / in (time) /" "$s"/*.txt
}

if [ "${1:-}" = "--against" ]; then
  rev=${2:?usage: compare-results.sh --against REV}
  top=$(git rev-parse --show-toplevel)
  tmp=$(mktemp -d)
  git -C "$top" worktree add --detach "$tmp/old" "$rev" >/dev/null
  (cd "$tmp/old" && CARGO_TARGET_DIR="$top/target/compare-old" cargo build --release --locked -q)
  (cd "$top" && cargo build --release --locked -q)
  (cd "$tmp/old" && run_all "$top/target/compare-old/release/cablevib" "$tmp/before")
  (cd "$top" && run_all "$top/target/release/cablevib" "$tmp/after")
  git -C "$top" worktree remove --force "$tmp/old"
  if diff -r "$tmp/before" "$tmp/after"; then echo "identical: $(find "$tmp/after" -type f | wc -l) files"; else exit 1; fi
else
  bin=${1:?usage: compare-results.sh BINARY OUTDIR | --against REV}
  out=${2:?usage: compare-results.sh BINARY OUTDIR | --against REV}
  run_all "$(realpath "$bin")" "$out"
  echo "wrote $(find "$out" -type f | wc -l) files to $out"
fi
