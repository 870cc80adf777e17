#!/usr/bin/env bash
# Two revisions timed against each other on this machine, in one run, runs
# alternating so that the machine's load falls on both alike: the issue-5
# workload's steady-state frame (bench_workload, library path) and the CLI
# end to end (the demo street as an EXR, camera-f8-7blade, kernel built).
#   bash bench/compare.sh OLD [NEW]   # revisions; NEW defaults to HEAD
#   RUNS=5 SIZE=1080p bash bench/compare.sh c66db20
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD
old=$1 new=${2:-HEAD} runs=${RUNS:-3} size=${SIZE:-4k}
work=$(mktemp -d)
trap 'git worktree remove --force "$work/tree" 2>/dev/null || true; rm -rf "$work"' EXIT
for side in old new; do
  rev=${!side}
  git worktree add -q --detach "$work/tree" "$rev"
  # One target folder: only the workspace's crates are built again.
  (cd "$work/tree" && CARGO_TARGET_DIR="$repo/target" \
    cargo build --release --locked -q -p aureole-tools --bin bench_workload &&
    CARGO_TARGET_DIR="$repo/target" cargo build --release --locked -q -p aureole-cli)
  cp target/release/bench_workload "$work/bench-$side"
  cp target/release/aureole "$work/aureole-$side"
  git worktree remove --force "$work/tree"
done
dims=$([ "$size" = 4k ] && echo 3840x2160 || echo 1920x1080)
"$work/aureole-new" demo -q --size "$dims" -o "$work/demo.png" --hdr "$work/street.exr"
echo "load before: $(uptime | sed 's/.*load average: //')"
for run in $(seq "$runs"); do
  for side in old new; do
    "$work/bench-$side" "$size" "$work/out-$side" >/dev/null
    python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(f'{sys.argv[2]} frame {d[\"median\"]*1e3:.1f} ms, kernel {d[\"kernel_build\"]:.2f} s')" \
      "$work/out-$side/aureole.json" "$side"
    python3 - "$work/aureole-$side" "$work" "$side" <<'PY'
import subprocess, sys, time
aureole, work, side = sys.argv[1:]
start = time.perf_counter()
subprocess.run([aureole, "apply", "-q", f"{work}/street.exr", "--preset", "camera-f8-7blade",
                "-o", f"{work}/out-{side}.exr"], check=True)
print(f"{side} apply {time.perf_counter() - start:.2f} s")
PY
  done
done
# The last outputs stay in bench/out/compare/ to be compared.
mkdir -p bench/out/compare
cp "$work/out-old.exr" "$work/out-new.exr" bench/out/compare/
cmp -s "$work/out-old.exr" "$work/out-new.exr" && echo "apply: the same bytes from both" ||
  echo "apply: the files differ (bench/out/compare/out-old.exr, out-new.exr)"
