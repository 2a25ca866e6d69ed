#!/usr/bin/env bash
# `cablevib simulate` speed, two binaries side by side: the paper's 10 s circle at 1 kHz and
# suspended-8's S-curve with sag, each run ROUNDS times alternating OLD and NEW so that a
# shared machine's load falls on both alike; prints each run's CPU time (user + sys, s) and
# wall time, then the medians. Extra simulate options per binary (e.g. the old default's
# --modes 48 that accuracy needed) go in OLD_ARGS / NEW_ARGS.
#
#   OLD_ARGS="--modes 48" scripts/bench-simulate.sh OLD_BINARY target/release/cablevib 3
#
# Needs python3 (standard library only) for the CPU times and medians.
set -euo pipefail
old=${1:?old binary}
new=${2:?new binary}
rounds=${3:-3}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

cases=(
  "circle|scenes/spatial_paper.toml --elements 10 --circle-s 10 --modal-ratio 0.02"
  "suspended-8 sag|scenes/suspended_8.toml --sag true --elements 10 --move 0.3,0,0 --duration 0.5 --modal-ratio 0.01"
)

run() { # binary, extra args, case args → "cpu wall"
  python3 - "$@" <<'EOF'
import resource, subprocess, sys, time
binary, extra, args, out = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
cmd = [binary, "simulate"] + args.split() + extra.split() + ["--out", out + "/run"]
t0 = time.monotonic()
r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
wall = time.monotonic() - t0
if p.returncode != 0:
    sys.exit(f"{' '.join(cmd)}: {p.stderr.strip()}")
cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
acc = [l for l in p.stdout.splitlines() if "accuracy:" in l or "mode updates" in l]
print(f"{cpu:.3f} {wall:.3f} | " + " | ".join(acc))
EOF
}

for c in "${cases[@]}"; do
  name=${c%%|*}
  args=${c#*|}
  : >"$out/old" && : >"$out/new"
  for ((i = 1; i <= rounds; i++)); do
    o=$(run "$old" "${OLD_ARGS:-}" "$args" "$out") && echo "$o" >>"$out/old"
    n=$(run "$new" "${NEW_ARGS:-}" "$args" "$out") && echo "$n" >>"$out/new"
    echo "$name round $i: old ${o%%|*}s  new ${n%%|*}s (cpu wall)"
  done
  echo "  old: $(tail -1 "$out/old" | cut -d'|' -f2-)"
  echo "  new: $(tail -1 "$out/new" | cut -d'|' -f2-)"
  python3 - "$name" "$out/old" "$out/new" <<'EOF'
import statistics, sys
name, old, new = sys.argv[1:]
med = lambda f, i: statistics.median(float(l.split()[i]) for l in open(f))
co, cn = med(old, 0), med(new, 0)
print(f"{name}: median CPU old {co:.2f} s, new {cn:.2f} s (x{co / cn:.2f}); median wall old {med(old, 1):.2f} s, new {med(new, 1):.2f} s")
EOF
done
