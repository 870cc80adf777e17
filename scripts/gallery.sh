#!/usr/bin/env bash
# Regenerates docs/gallery/ from the committed presets and configs/, the
# built-in demo scene and the photographs in ../shared/data:
#   bash scripts/gallery.sh
# Every picture is made by the release binary (and the `montage` and
# `star_rays` programs of tools/, which lay pictures side by side and count
# a star's rays); nothing is edited by hand. Without ../shared/data the pictures made
# from photographs are left as they are.
set -euo pipefail
cd "$(dirname "$0")/.."

cargo build --release --locked -q -p aureole-cli
cargo build --release --locked -q -p aureole-tools --bin montage --bin star_rays
aureole=target/release/aureole
montage=target/release/montage
star_rays=$PWD/target/release/star_rays
out=docs/gallery
data=../shared/data
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"

# A kernel as a log-scaled picture (6 decades), from presets or configs.
kernel() { # kernel OUT.png SIZE IMAGE_WIDTH CAMERA-ARGS...
  local png=$1 size=$2 width=$3
  shift 3
  "$aureole" psf -q "$@" --size "$size" --image-width "$width" -o "$png"
}

# A config for one aperture or bloom variant, written into $work.
camera() { # camera NAME F_NUMBER: a full-frame 50 mm camera, no effect yet
  printf '[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = 50.0\nf_number = %s\n' "$2" >"$work/$1.toml"
}
stop() { # stop NAME F_NUMBER BLADES ROUNDNESS
  camera "$1" "$2"
  printf '\n[[effect]]\ntype = "aperture"\nblades = %s\nroundness = %s\n' "$3" "$4" >>"$work/$1.toml"
}
bloom() { # bloom NAME EPSILON
  cat >"$work/$1.toml" <<EOF
[[effect]]
type = "bloom"
epsilon = $2
beta = 2.0
radius = "10.4px"
EOF
}

# --- README's opening picture: the demo street without and with a lens.
"$aureole" demo -q --size 1280x720 -o "$work/demo.png" --hdr "$work/demo.exr"
"$aureole" apply -q "$work/demo.exr" --threshold 1e12 --white 6 -o "$work/demo-none.png"
"$aureole" apply -q "$work/demo.exr" --preset camera-f8-7blade --white 6 -o "$work/demo-f8.png"
"$montage" "$out/hero.jpg" --width 640 \
  "$work/demo-none.png=the scene (cd/m2), no camera" \
  "$work/demo-f8.png=aureole apply --preset camera-f8-7blade"

# --- The paper's figures.
# Fig. 4 left (bloom) and Fig. 5 left (corona, 14 rays): kernel and profiles.
for preset in paper-fig4-bloom paper-fig5-corona; do
  "$aureole" psf -q --preset "$preset" --size 301 -o "$out/$preset-kernel.png" \
    --profile "$out/$preset-profile.png"
done
# Fig. 6: the four coronas side by side.
for panel in a b c d; do
  "$aureole" psf -q --preset "paper-fig6$panel" --size 301 -o "$work/fig6$panel.png"
done
"$montage" "$out/paper-fig6.png" \
  "$work/fig6a.png=(a) s = -1, w = 10 px" "$work/fig6b.png=(b) s = 0, w = 3 px" \
  "$work/fig6c.png=(c) s = 0.5, w = 3 px" "$work/fig6d.png=(d) s = 1, w = 3 px"
# Fig. 4/5 right: bloom, corona and both on the demo street...
"$aureole" demo -q --size 960x540 -o "$work/street.png" --hdr "$work/street.exr"
"$aureole" apply -q "$work/street.exr" --threshold 1e12 --white 6 -o "$work/street-none.png"
for preset in paper-fig4-bloom paper-fig5-corona paper-fig5-both; do
  "$aureole" apply -q "$work/street.exr" --preset "$preset" --white 6 -o "$work/street-$preset.png"
done
"$montage" "$out/paper-fig45-demo.jpg" --columns 2 --width 640 \
  "$work/street-none.png=no camera" "$work/street-paper-fig4-bloom.png=bloom (Fig. 4)" \
  "$work/street-paper-fig5-corona.png=corona (Fig. 5)" "$work/street-paper-fig5-both.png=both (Fig. 5)"

# --- Photographs (licences: docs/gallery/LICENSES.md).
presets=(paper-fig4-bloom paper-fig5-corona camera-f8-7blade star-filter-6pt human-eye-vos)
photo() { # photo NAME FILE THRESHOLD CROP|- APPLY-ARGS...
  local name=$1 file=$2 threshold=$3 crop=$4
  shift 4
  local framing=()
  [ "$crop" != - ] && framing=(--crop "$crop")
  "$aureole" apply -q "$data/$file" "$@" --threshold 1e12 -o "$work/$name-none.png"
  local panels=("$work/$name-none.png=$file, no camera")
  for preset in "${presets[@]}"; do
    "$aureole" apply -q "$data/$file" "$@" --preset "$preset" --threshold "$threshold" \
      -o "$work/$name-$preset.png"
    panels+=("$work/$name-$preset.png=$preset")
  done
  "$montage" "$out/photo-$name.jpg" --columns 3 --width 420 --quality 85 "${framing[@]}" "${panels[@]}"
}
if [ -d "$data" ]; then
  # Night: the bridge's lamps at 1.5x, the sky's stars, a lamp in fog, a candle.
  photo goldengate GoldenGate.exr 10 830,380,280,140 --white 1
  photo dikhololo dikhololo_night_1k.hdr 5 - --white 1
  photo fog Fog.exr 5 -
  photo candleglass CandleGlass.exr 10 -
  # Day: a sky of 10^3-10^4 cd/m² behind a tree (calibrated: whiteLuminance).
  photo tree Tree.exr 3000 -

  # Fig. 4/5 right on a real night photograph: the same crop of the bridge.
  for preset in paper-fig4-bloom paper-fig5-corona paper-fig5-both; do
    "$aureole" apply -q "$data/GoldenGate.exr" --preset "$preset" --threshold 10 --white 1 \
      -o "$work/gg-$preset.png"
  done
  "$montage" "$out/paper-fig45-goldengate.jpg" --columns 2 --width 560 --crop 830,380,280,140 \
    "$work/goldengate-none.png=no camera" "$work/gg-paper-fig4-bloom.png=bloom (Fig. 4)" \
    "$work/gg-paper-fig5-corona.png=corona (Fig. 5)" "$work/gg-paper-fig5-both.png=both (Fig. 5)"

  # A real star: CandleGlass.exr, f/32. Its rays, measured above the candle
  # (the candle hides 200-340°, the glass lies beyond 110 px to the right).
  "$star_rays" "$data/CandleGlass.exr" --radii 60,110 --exclude 200,340 --min-ratio 1.05 \
    | tee "$out/candleglass-rays.txt"
  flame=$(awk '/total luminance/ { print $(NF-3) }' "$out/candleglass-rays.txt")
  # The 401-px square centred on the light.
  square=$(awk -F'[(), ]+' '/light at/ { for (i = 1; i < NF; i++) if ($i == "at") \
    printf "%d,%d,401,401", $(i+1) - 200 + 0.5, $(i+2) - 200 + 0.5 }' "$out/candleglass-rays.txt")
  "$aureole" apply -q "$data/CandleGlass.exr" --threshold 1e12 --white 0.05 \
    -o "$work/candle-photo.png"
  "$montage" "$work/candle-crop.png" --gap 0 --crop "$square" "$work/candle-photo.png"
  # A point light of the flame's luminance × area through the lens we read
  # from the photo, shown at the same white; and with straight blades.
  sed 's/^roundness = .*/roundness = 0.0/' configs/candleglass-f32-8blade.toml >"$work/straight.toml"
  for lens in configs/candleglass-f32-8blade.toml "$work/straight.toml"; do
    name=$(basename "$lens" .toml)
    "$aureole" psf -q --config "$lens" --size 401 --image-width 1000 -o "$work/$name.exr"
    (cd "$work" && "$star_rays" "$name.exr" --radii 60,110 --min-ratio 1.05) |
      tee -a "$out/candleglass-rays.txt"
    "$aureole" apply -q "$work/$name.exr" --input-scale "$flame" --threshold 1e12 --white 0.05 \
      -o "$work/$name.png"
  done
  "$montage" "$out/candleglass-star.jpg" --quality 85 \
    "$work/candle-crop.png=CandleGlass.exr, f/32" \
    "$work/candleglass-f32-8blade.png=8 blades, f/32, roundness 0.1" \
    "$work/straight.png=8 straight blades, f/32"

  # Auto exposure, before and now. "Before" is the white the log-average
  # meter (9.6 L̄) chose for these very runs, measured before it was
  # replaced by the lit-scene meter (docs/physics.md §9).
  exposure() { # exposure NAME INPUT OLD_WHITE
    "$aureole" apply -q "$2" --max-kernel 257 --white "$3" -o "$work/ae-$1-before.png"
    "$aureole" apply -q "$2" --max-kernel 257 -o "$work/ae-$1-now.png"
  }
  exposure street "$work/demo.exr" 1.53
  exposure candle "$data/CandleGlass.exr" 0.00626
  exposure goldengate "$data/GoldenGate.exr" 0.622
  exposure tree "$data/Tree.exr" 473
  "$montage" "$out/auto-exposure.jpg" --columns 2 --width 400 \
    "$work/ae-street-before.png=demo street: log-average meter (before)" \
    "$work/ae-street-now.png=lit-scene meter (now)" \
    "$work/ae-candle-before.png=CandleGlass: before" "$work/ae-candle-now.png=now" \
    "$work/ae-goldengate-before.png=GoldenGate: before" "$work/ae-goldengate-now.png=now" \
    "$work/ae-tree-before.png=Tree (day, backlit): before" "$work/ae-tree-now.png=now"

  # Recipes of the guide (configs/) on scenes that suit them.
  "$aureole" apply -q "$work/demo.exr" --config configs/night-street.toml --white 6 -o "$work/r1.png"
  "$aureole" apply -q "$data/CandleGlass.exr" --config configs/candle-interior.toml \
    -o "$work/r2.png"
  "$aureole" apply -q "$data/dikhololo_night_1k.hdr" --config configs/astro-spikes.toml --white 1 \
    -o "$work/r3.png"
  "$aureole" apply -q "$data/GoldenGate.exr" --config configs/star-filter.toml --threshold 10 --white 1 \
    -o "$work/r4.png"
  "$montage" "$work/r1c.png" --gap 0 --width 480 "$work/r1.png"
  "$montage" "$work/r2c.png" --gap 0 --width 480 --crop 100,100,800,450 "$work/r2.png"
  "$montage" "$work/r3c.png" --gap 0 --width 480 --crop 112,31,800,450 "$work/r3.png"
  "$montage" "$work/r4c.png" --gap 0 --width 480 --crop 690,300,480,270 "$work/r4.png"
  "$montage" "$out/guide-recipes-applied.jpg" --columns 2 --quality 85 \
    "$work/r1c.png=night-street.toml (demo)" "$work/r2c.png=candle-interior.toml" \
    "$work/r3c.png=astro-spikes.toml" "$work/r4c.png=star-filter.toml"

  # Halation: the bridge's lamps on film without and with its backing.
  for preset in film-35mm-no-remjet film-35mm-remjet; do
    "$aureole" apply -q "$data/GoldenGate.exr" --preset "$preset" --threshold 10 --white 1 \
      -o "$work/gg-$preset.png"
  done
  "$montage" "$out/guide-halation.jpg" --width 420 --quality 85 --crop 830,380,280,140 \
    "$work/goldengate-none.png=no camera" "$work/gg-film-35mm-no-remjet.png=film-35mm-no-remjet" \
    "$work/gg-film-35mm-remjet.png=film-35mm-remjet"
else
  echo "gallery: $data not found: the pictures of photographs are left as they are" >&2
fi

# --- The guide's pictures of each parameter.
for blades in 5 6 7 8 9 0; do stop "blades$blades" 11 "$blades" 0.0; done
for b in 5 6 7 8 9 0; do kernel "$work/blades$b.png" 201 1500 --config "$work/blades$b.toml"; done
"$montage" "$out/guide-blades.png" --columns 6 \
  "$work/blades5.png=5: 10 rays" "$work/blades6.png=6: 6 rays" "$work/blades7.png=7: 14 rays" \
  "$work/blades8.png=8: 8 rays" "$work/blades9.png=9: 18 rays" "$work/blades0.png=round: none"
for n in 4 8 16 32; do
  stop "f$n" "$n" 7 0.0
  kernel "$work/f$n.png" 201 1500 --config "$work/f$n.toml"
done
"$montage" "$out/guide-fnumber.png" \
  "$work/f4.png=f/4" "$work/f8.png=f/8" "$work/f16.png=f/16" "$work/f32.png=f/32"
for r in 0.0 0.1 0.4 1.0; do
  stop "round$r" 16 8 "$r"
  kernel "$work/round$r.png" 201 1500 --config "$work/round$r.toml"
done
"$montage" "$out/guide-roundness.png" \
  "$work/round0.0.png=roundness 0" "$work/round0.1.png=0.1" "$work/round0.4.png=0.4" \
  "$work/round1.0.png=1 (a circle)"
for preset in film-35mm-no-remjet film-35mm-remjet; do
  kernel "$work/$preset.png" 201 1920 --preset "$preset"
done
"$montage" "$out/guide-halation-kernels.png" \
  "$work/film-35mm-no-remjet.png=no remjet" \
  "$work/film-35mm-remjet.png=remjet"
stop clean 4 7 0.0
cp "$work/clean.toml" "$work/dirty.toml"
cat >>"$work/dirty.toml" <<EOF
dust = 60
scratches = 3
scratch_width_um = 30
grease = 0.3
EOF
kernel "$work/clean.png" 301 3840 --config "$work/clean.toml"
kernel "$work/dirty.png" 301 3840 --config "$work/dirty.toml" --pupil "$work/pupil.png"
"$montage" "$out/guide-dirt.png" --width 400 \
  "$work/clean.png=clean" "$work/dirty.png=dust, scratches, grease" "$work/pupil.png=its pupil"
for e in 0.002 0.01 0.05; do
  bloom "bloom$e" "$e"
  "$aureole" apply -q "$work/street.exr" --config "$work/bloom$e.toml" --white 6 -o "$work/bloom$e.png"
done
"$montage" "$out/guide-bloom.jpg" --crop 0,120,480,270 --width 400 \
  "$work/street-none.png=no camera" "$work/bloom0.002.png=epsilon 0.002" \
  "$work/bloom0.01.png=epsilon 0.01" "$work/bloom0.05.png=epsilon 0.05"
for t in 0 100 5000; do
  "$aureole" apply -q "$work/street.exr" --preset paper-fig5-corona --config "$work/bloom0.05.toml" \
    --threshold "$t" --white 6 -o "$work/threshold$t.png"
done
"$montage" "$out/guide-threshold.jpg" --width 420 \
  "$work/threshold0.png=threshold 0" "$work/threshold100.png=threshold 100 cd/m2" \
  "$work/threshold5000.png=threshold 5000 cd/m2"
# Lens ghosts: the demo street through the double-Gauss of US 4,247,171
# (7 blades) at f/2 and f/8, and its ghosts alone, far brighter.
ghosts() { # ghosts NAME F_NUMBER BLADES (0: a round stop, no aperture)
  camera "$1" "$2"
  printf '\n[[effect]]\ntype = "ghosts"\nlens = "double-gauss-50mm-f1.4"\n' >>"$work/$1.toml"
  if [ "$3" != 0 ]; then printf '\n[[effect]]\ntype = "aperture"\nblades = %s\n' "$3" >>"$work/$1.toml"; fi
}
for n in 2 8; do
  ghosts "ghosts-f$n" "$n" 7
  "$aureole" apply -q "$work/street.exr" --config "$work/ghosts-f$n.toml" --white 6 -o "$work/ghosts-f$n.png"
  ghosts "alone-f$n" "$n" 0
  "$aureole" apply -q "$work/street.exr" --config "$work/alone-f$n.toml" --glare-only --white 0.2 \
    -o "$work/alone-f$n.png"
done
"$montage" "$out/guide-ghosts.jpg" --columns 2 --width 480 --quality 85 \
  "$work/ghosts-f2.png=f/2, 7 blades: ghosts and rays" "$work/ghosts-f8.png=f/8" \
  "$work/alone-f2.png=f/2: the ghosts alone (round stop), 30x brighter" \
  "$work/alone-f8.png=f/8: the ghosts alone, 30x brighter"
# Ghosts that move: a headlamp crossing a dark night through the
# double-Gauss at f/4 (its ghosts cross the other way, through the
# centre), and the sun by day at f/11. The scenes are written here.
python3 - "$work" <<'PY'
import sys
from array import array
work, width, height = sys.argv[1], 960, 540


def write(name, rows):
    """A PFM of RGB rows, top first (the format stores them bottom first)."""
    pixels = array("f")
    for row in reversed(rows):
        pixels.extend(row)
    if sys.byteorder == "big":
        pixels.byteswap()
    with open(f"{work}/{name}.pfm", "wb") as out:
        out.write(b"PF\n%d %d\n-1.0\n" % (width, height))
        out.write(pixels.tobytes())


def scene(sky, ground, horizon, *spots):
    """Sky above the horizon and ground below (cd/m², RGB), and round
    white sources (x, y, radius, cd/m²)."""
    rows = []
    for y in range(height):
        row = array("f", sky(y) if y < horizon else ground) * width
        for x0, y0, radius, value in spots:
            if abs(y - y0) <= radius:
                for x in range(max(0, int(x0 - radius)), min(width, int(x0 + radius) + 1)):
                    if (x - x0) ** 2 + (y - y0) ** 2 <= radius * radius:
                        row[3 * x:3 * x + 3] = array("f", [value] * 3)
        rows.append(row)
    return rows


# A headlamp of 2·10⁵ cd/m² crossing a night of 0.01–0.2 cd/m².
night = lambda y: [0.01 + 0.02 * y / height] * 3
for k, x in enumerate((150, 360, 600, 810)):
    write(f"crossing{k}", scene(night, [0.05, 0.045, 0.04], 380, (x, 300, 1.5, 2e5)))
# The sun (1.6·10⁹ cd/m², 0.53° across: 12 px at 50 mm on a 36 mm sensor
# 960 px wide) in a blue sky of 3000–8000 cd/m² over a meadow of 1000.
sky = lambda y: [(8000 - 5000 * y / 380) * c for c in (0.75, 0.95, 1.3)]
write("sun", scene(sky, [900.0, 1100.0, 500.0], 380, (250, 110, 6.0, 1.6e9)))
# Two headlamps, for the anamorphic streak.
write("headlamps", scene(night, [0.05, 0.045, 0.04], 380, (330, 290, 1.5, 2e5), (600, 290, 1.5, 2e5)))
PY
ghosts "moving" 4 7
for k in 0 1 2; do
  "$aureole" apply -q "$work/crossing$k.pfm" --config "$work/moving.toml" --white 1 \
    -o "$work/crossing$k.png"
done
ghosts "sun" 11 7
"$aureole" apply -q "$work/sun.pfm" --config "$work/sun.toml" --white 15000 -o "$work/sun.png"
"$montage" "$out/guide-ghosts-moving.jpg" --columns 2 --width 480 --quality 85 \
  "$work/crossing0.png=f/4: a lamp, its ghosts opposite" \
  "$work/crossing1.png=nearer the centre, they close in" \
  "$work/crossing2.png=past it, they cross over" \
  "$work/sun.png=the sun by day at f/11"
# The anamorphic streak: the two headlamps written above through the
# rear anamorphic (a Super 35 camera at 100 mm, f/2.8, its stop squeezed
# alike) and through the double-Gauss at the same focal length, and the
# demo street through the anamorphic, with its ghosts alone.
cine() { # cine NAME LENS SQUEEZE
  printf '[camera]\nsensor_width_mm = 24.9\nfocal_length_mm = 100.0\nf_number = 2.8\n' >"$work/$1.toml"
  printf '\n[[effect]]\ntype = "ghosts"\nlens = "%s"\n' "$2" >>"$work/$1.toml"
  printf '\n[[effect]]\ntype = "aperture"\nblades = 0\nsqueeze = %s\n' "$3" >>"$work/$1.toml"
}
cine anamorphic anamorphic-rear-1.3x-f1.8 1.301
cine spherical double-gauss-50mm-f1.4 1
"$aureole" apply -q "$work/headlamps.pfm" --config "$work/anamorphic.toml" --white 1 -o "$work/lamps-anamorphic.png"
"$aureole" apply -q "$work/headlamps.pfm" --config "$work/spherical.toml" --white 1 -o "$work/lamps-spherical.png"
"$aureole" apply -q "$work/street.exr" --config "$work/anamorphic.toml" --white 6 -o "$work/street-anamorphic.png"
"$aureole" apply -q "$work/street.exr" --config "$work/anamorphic.toml" --glare-only --white 0.2 \
  -o "$work/alone-anamorphic.png"
"$montage" "$out/guide-ghosts-anamorphic.jpg" --columns 2 --width 480 --quality 85 \
  "$work/lamps-anamorphic.png=rear anamorphic 1.3x, f/2.8: the streak" \
  "$work/lamps-spherical.png=the double-Gauss at 100 mm, f/2.8" \
  "$work/street-anamorphic.png=the street through the anamorphic" \
  "$work/alone-anamorphic.png=its ghosts and glare alone, 30x brighter"
for recipe in configs/*.toml; do
  kernel "$work/recipe-$(basename "$recipe" .toml).png" 257 1000 --config "$recipe"
done
"$montage" "$out/guide-recipes.png" --columns 3 \
  "$work/recipe-night-street.png=night-street" "$work/recipe-candle-interior.png=candle-interior" \
  "$work/recipe-sun-through-trees.png=sun-through-trees" "$work/recipe-astro-spikes.png=astro-spikes" \
  "$work/recipe-star-filter.png=star-filter" "$work/recipe-candleglass-f32-8blade.png=candleglass-f32-8blade"

# Glare figures: an office with a sunlit window rendered by Radiance
# (pyradiance's rpict, the scene of the evalglare comparison test), its two
# glare sources marked. Without pyradiance the pictures are left as they are.
py=target/pyvenv/bin/python
if [ -x "$py" ] && "$py" -c 'import pyradiance' 2>/dev/null; then
  # Renders a scene of the test: NAME FOLDER SIZE [VIEW HEIGHT].
  scene() {
    mkdir -p "$2"
    "$py" - "$@" <<'PY'
import sys
sys.path.insert(0, "crates/aureole-py/tests")
from glare_scenes import radiance_bin, render
name, folder, size = sys.argv[1], sys.argv[2], int(sys.argv[3])
view, height = (sys.argv[4], int(sys.argv[5])) if len(sys.argv) > 5 else (None, None)
render(radiance_bin(), name, folder, size, view=view, height=height)
PY
  }
  # A view's DGP and UGR, for a caption.
  figures() {
    "$aureole" -q glare "$1" --json | "$py" -c \
      'import json, sys; f = json.load(sys.stdin); print("DGP %.2f, UGR %.0f" % (f["dgp"], f["ugr"]))'
  }
  scene office-sun "$work" 400
  "$aureole" -q glare "$work/office-sun.hdr" -c "$out/glare-office-marked.png" > /dev/null
  # The guide's night street for architects: the same street seen through
  # a 90° perspective, as a camera at f/8 records it and as a 25- and a
  # 70-year-old see it (the CIE's eye), one exposure for all three.
  scene night-street "$work" 960 "-vtv -vh 90 -vv 58.7" 540
  printf '[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = 18.0\n' > "$work/lens-18mm.toml"
  for preset in camera-f8-7blade human-eye-cie-25 human-eye-cie-70; do
    "$aureole" -q apply "$work/night-street.hdr" -o "$work/street-$preset.png" --preset "$preset" \
      --config "$work/lens-18mm.toml" --input-scale 179 --exposure 7.5
  done
  "$montage" "$out/guide-glare-observers.jpg" --columns 3 --width 480 --quality 85 \
    "$work/street-camera-f8-7blade.png=camera f/8: $(figures "$work/night-street.hdr")" \
    "$work/street-human-eye-cie-25.png=a 25-year-old (CIE 146)" \
    "$work/street-human-eye-cie-70.png=a 70-year-old with light eyes"
  # The same street as a 180° fisheye, the eye spread over the sphere of
  # its directions (the view from the picture's VIEW header).
  scene night-street "$work/fisheye" 600
  fisheye="$work/fisheye/night-street.hdr"
  # The scene itself: a bloom with a threshold no pixel reaches.
  "$aureole" -q apply "$fisheye" -o "$work/fisheye-scene.png" --config "$work/lens-18mm.toml" \
    --preset paper-fig4-bloom --input-scale 179 --exposure 7.5 --threshold 1e12
  for preset in human-eye-cie-25 human-eye-cie-70; do
    "$aureole" -q apply "$fisheye" -o "$work/fisheye-$preset.png" --preset "$preset" \
      --input-scale 179 --exposure 7.5 --threshold 500
  done
  "$montage" "$out/guide-glare-fisheye.jpg" --columns 3 --width 400 --quality 85 \
    "$work/fisheye-scene.png=the scene: $(figures "$fisheye")" \
    "$work/fisheye-human-eye-cie-25.png=a 25-year-old" \
    "$work/fisheye-human-eye-cie-70.png=a 70-year-old, light eyes"
fi

ls -la "$out"
