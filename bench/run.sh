#!/usr/bin/env bash
# The issue-5 benchmark: aureole's library path and its peers on the same
# workload, in one run, on this machine. Writes bench/RESULTS.md.
#   bash bench/run.sh            # 1080p and 4K
#   SIZES=1080p bash bench/run.sh
set -euo pipefail
cd "$(dirname "$0")/.."
sizes=${SIZES:-"1080p 4k"}
venv=bench/.venv
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet numpy scipy opencv-python-headless
fi
# Optional: the FFTW row appears when pyFFTW installs.
# The end-to-end peer reads and writes EXR with the OpenEXR package.
"$venv/bin/python" -c "import OpenEXR" 2>/dev/null || "$venv/bin/pip" install --quiet OpenEXR
if ! "$venv/bin/python" -c "import pyfftw" 2>/dev/null; then
  "$venv/bin/pip" install --quiet pyfftw || echo "pyFFTW did not install: its row is left out"
fi
peers=("numpy/scipy rfft2, cached kernel spectrum" "scipy.signal.fftconvolve" "scipy.signal.fftconvolve (2 workers)" "scipy.signal.oaconvolve" "cv2.filter2D")
if "$venv/bin/python" -c "import pyfftw" 2>/dev/null; then
  peers+=("pyFFTW rfft2 (FFTW, 2 threads, measured plans), cached kernel spectrum")
fi
cargo build --release --locked -p aureole-tools --bin bench_workload --bin bench_codec
cargo build --release --locked -p aureole-cli
{
  echo "# Benchmark results"
  echo
  echo "Produced by \`bash bench/run.sh\` on $(nproc) cores ($(uname -m)), $(date -u +%Y-%m-%d), load before the run: $(uptime | sed "s/.*load average: //")."
  echo "Workload of issue 5 (3 channels, full-frame kernel, threshold 0); times are the"
  echo "steady state (kernel and its spectrum built beforehand where the tool allows),"
  echo "median of 6 runs after a warm-up. Agreement: relative L2 difference to aureole."
  echo
} > bench/RESULTS.md
for size in $sizes; do
  out=bench/out/$size
  ./target/release/bench_workload "$size" "$out"
  rows=$(mktemp)
  for peer in "${peers[@]}"; do
    "$venv/bin/python" bench/peers.py "$out" "$peer" >> "$rows" || echo "{\"peer\": \"$peer\", \"failed\": true}" >> "$rows"
  done
  "$venv/bin/python" - "$out/aureole.json" "$rows" "$size" >> bench/RESULTS.md <<'PY'
import json, sys
ours = json.load(open(sys.argv[1]))
rows = [json.loads(line) for line in open(sys.argv[2]) if line.strip()]
print(f"## {sys.argv[3]}\n")
print(f"aureole kernel build (bloom + corona, full frame): {ours['kernel_build']:.2f} s\n")
print("| implementation | median | min | max | ratio to aureole | peak memory | agreement |")
print("|---|---|---|---|---|---|---|")
print(f"| aureole (frame sequence: previous frame's planes reused) | {ours['median']*1e3:.0f} ms | {ours['min']*1e3:.0f} ms | {ours['max']*1e3:.0f} ms | 1.0 | {ours['peak_mb']:.0f} MB | reference |")
print(f"| aureole (fresh output planes) | {ours['fresh_median']*1e3:.0f} ms | {ours['fresh_min']*1e3:.0f} ms | {ours['fresh_max']*1e3:.0f} ms | {ours['fresh_median']/ours['median']:.1f} | | same |")
for r in rows:
    if r.get("failed"):
        print(f"| {r['peer']} | failed | | | | | |")
        continue
    ok = "ok" if r["difference"] < 1e-4 else "DIFFERS"
    print(f"| {r['peer']} | {r['median']*1e3:.0f} ms | {r['min']*1e3:.0f} ms | {r['max']*1e3:.0f} ms | {r['median']/ours['median']:.1f} | {r['peak_mb']:.0f} MB | {r['difference']:.1e} {ok} |")
print()
PY
  rm -f "$rows"
done
# End to end (EXR in, EXR out, batches through the CLI) against OpenEXR +
# scipy, on the demo night street and, at 4K, the workload scene above; the
# kernel files; the codecs against OpenEXR on the 4K night street through
# the camera.
if [ -f bench/out/4k/image.npy ]; then
  "$venv/bin/python" bench/e2e.py target/release/aureole target/release/bench_codec "$(mktemp -d)" bench/out/4k >> bench/RESULTS.md
fi
work=$(mktemp -d)
./target/release/aureole demo --size 3840x2160 --hdr "$work/street.exr" -o "$work/street.png" -q
./target/release/aureole apply "$work/street.exr" --preset camera-f8-7blade -o "$work/camera.exr" -q
"$venv/bin/python" bench/codec.py target/release/bench_codec "$work/camera.exr" "$work/codec" >> bench/RESULTS.md
rm -rf "$work"
# Lens kernels and the studio's previews on the GPU too where this machine
# has one (a small kernel built there is the test).
probe=$(mktemp -d)
devices=cpu
if ./target/release/aureole psf --preset paper-fig4-bloom --size 33x33 --device gpu -q -o "$probe/k.pfm" 2>/dev/null; then
  devices=cpu,gpu
fi
rm -rf "$probe"
# Lens kernels: every preset, the dusty lens and issue 42's bloom with
# corona at 4K, the build alone as `psf` reports it and with writing.
{ echo "## Lens kernels (\`python3 bench/kernels.py --devices $devices\`, medians of 3)"; echo; python3 bench/kernels.py target/release/aureole --devices "$devices"; echo; } >> bench/RESULTS.md
# The studio: from a changed parameter to the new picture, each effect.
{
  echo "## The studio after a change (\`python3 bench/studio_latency.py --device D\`)"
  echo
  for device in ${devices//,/ }; do
    echo '```text'
    python3 bench/studio_latency.py --device "$device"
    echo '```'
    echo
  done
} >> bench/RESULTS.md
# The --max-memory estimate against the measured peaks of whole runs.
{ echo "## Memory: the estimate against measured peaks"; echo; python3 bench/memory.py target/release/aureole; echo; } >> bench/RESULTS.md
# Glare figures against Radiance's evalglare (pyradiance in the tests' venv).
if [ -x target/pyvenv/bin/python ] && target/pyvenv/bin/python -c 'import pyradiance' 2>/dev/null; then
  { echo "## Glare figures against evalglare (\`bench/glare.py\`, medians of 5)"; echo; target/pyvenv/bin/python bench/glare.py target/release/aureole; echo; } >> bench/RESULTS.md
fi
# The OpenFX plugin in the repository's host against the command line.
bash bench/ofx.sh >> bench/RESULTS.md
cat bench/RESULTS.md
