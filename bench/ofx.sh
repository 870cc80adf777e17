#!/usr/bin/env bash
# The OpenFX plugin's speed: the 4K night street through the plugin in the
# repository's host (ofx-render: one instance, a sequence of frames, the
# host's buffers reused as a host's image cache does), against `aureole
# apply`'s camera time on the same frame, as a still and as a sequence.
# Prints a Markdown section for bench/RESULTS.md.
#   bash bench/ofx.sh                 # FRAMES=5 RUNS=3 PRESET=camera-f8-7blade
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${FRAMES:-5}
runs=${RUNS:-3}
preset=${PRESET:-camera-f8-7blade}
cargo build --release --locked -q -p aureole-cli -p aureole-ofx -p aureole-ofx-host
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scripts/ofx-bundle --binary target/release/libaureole_ofx.so --out "$work/plugins" > /dev/null
./target/release/aureole demo --size 3840x2160 --hdr "$work/street.exr" -o "$work/street.png" -q
for i in $(seq 1 "$frames"); do
  cp "$work/street.exr" "$(printf "$work/s.%04d.exr" "$i")"
done
mkdir -p "$work/out"
load=$(uptime | sed "s/.*load average: //")
for run in $(seq 1 "$runs"); do
  ./target/release/ofx-render "$work/plugins/Aureole.ofx.bundle" "$work/street.exr" \
    --preset "$preset" --frames "$frames" >> "$work/plugin.json"
  ./target/release/aureole apply "$work/street.exr" --preset "$preset" --device cpu \
    -o "$work/still.exr" 2>&1 | grep -o "camera [0-9.]* s" >> "$work/still.txt"
  ./target/release/aureole apply "$work/s.%04d.exr" --frames "1-$frames" --preset "$preset" \
    --device cpu -o "$work/out/s.%04d.exr" 2>&1 | grep -o "camera [0-9.]* s" > "$work/batch.$run.txt"
done
python3 - "$work" "$frames" "$runs" "$preset" "$load" <<'PY'
import glob, json, statistics, sys
work, frames, runs, preset, load = sys.argv[1:6]
median = statistics.median
plugin = [json.loads(line)["frames"] for line in open(f"{work}/plugin.json")]
seconds = lambda line: float(line.split()[1])
still = [seconds(line) for line in open(f"{work}/still.txt")]
batches = [[seconds(line) for line in open(path)] for path in sorted(glob.glob(f"{work}/batch.*.txt"))]
first = median(p[0] for p in plugin)
later = median(t for p in plugin for t in p[1:])
cli_first = median(b[0] for b in batches)
cli_later = median(t for b in batches for t in b[1:])
print(f"## The OpenFX plugin: a 4K night street in the test host\n")
print(f"`bash bench/ofx.sh`: {runs} runs of a {frames}-frame sequence, `{preset}`, on the CPU; load before: {load}.")
print("The plugin's time is the host's whole render call (regions asked, images")
print("fetched and converted, the frame spread, the output written); the command")
print("line's is its summary's `camera` time (read and write apart).\n")
print("| | first frame (the kernel built) | each later frame (median) |")
print("|---|---|---|")
print(f"| plugin in `ofx-render` | {first:.2f} s | {later:.2f} s |")
print(f"| `aureole apply`, a still | {median(still):.2f} s | |")
print(f"| `aureole apply`, a {frames}-frame sequence | {cli_first:.2f} s | {cli_later:.2f} s |")
print(f"| plugin ÷ sequence | {first / cli_first:.2f} | {later / cli_later:.2f} |")
print()
PY
