#!/usr/bin/env bash
# Regenerates docs/gallery/ from the committed presets, the built-in demo
# scene and the photographs in ../shared/data (when present):
#   bash scripts/gallery.sh
# Every picture is made by the release binary; nothing is edited by hand.
set -euo pipefail
cd "$(dirname "$0")/.."

cargo build --release --locked -q
aureole=target/release/aureole
out=docs/gallery
data=../shared/data
mkdir -p "$out"

# The paper's filters as kernels (log-scaled pictures) with their radial and
# angular profiles: Fig. 4 left (bloom), Fig. 5 left (corona, 14 rays) and
# the four coronas of Fig. 6 (s = -1, 0, 0.5, 1).
for preset in paper-fig4-bloom paper-fig5-corona paper-fig6a paper-fig6b paper-fig6c paper-fig6d; do
  "$aureole" psf -q --preset "$preset" --size 301 -o "$out/$preset-kernel.png" \
    --profile "$out/$preset-profile.png"
done

# Fig. 4/5 right: bloom, corona and both, on the demo night street...
"$aureole" demo -q --size 960x540 -o "$out/demo-before.png" --hdr "$out/.demo.exr" --preset paper-fig4-bloom
for preset in paper-fig4-bloom paper-fig5-corona paper-fig5-both; do
  "$aureole" apply -q "$out/.demo.exr" --preset "$preset" -o "$out/demo-$preset.jpg"
done
# ... without any camera, at the same exposure as the demo's result.
"$aureole" apply -q "$out/.demo.exr" --preset paper-fig4-bloom --threshold 1e12 -o "$out/demo-none.jpg"
rm -f "$out/.demo.exr" "$out/demo-before.png"

# ... and on a real night photograph (GoldenGate.exr, BSD-3-Clause, ILM:
# see docs/gallery/LICENSES.md).
if [ -f "$data/GoldenGate.exr" ]; then
  "$aureole" apply -q "$data/GoldenGate.exr" --preset paper-fig4-bloom --threshold 1e12 \
    -o "$out/goldengate-none.jpg"
  for preset in paper-fig4-bloom paper-fig5-corona paper-fig5-both; do
    "$aureole" apply -q "$data/GoldenGate.exr" --preset "$preset" --threshold 10 \
      -o "$out/goldengate-$preset.jpg"
  done
else
  echo "gallery: $data/GoldenGate.exr not found: the photograph rows are left as they are" >&2
fi
ls -la "$out"
