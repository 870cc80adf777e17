// The GPU engine's kernels (docs/physics.md §8): Stockham FFT passes of
// radix 2, 3, 4 and 5 along rows or columns of the padded grid, the
// spectrum multiply that splits two real planes packed as one complex
// plane, and the loads and finishes between the frame and the grid.
// Twiddles come from a table computed in f64 on the host: the GPU's own
// sin and cos are not accurate enough for a 1e-5 match with the CPU.

fn mul(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}

// z·(s·i) for the transform's sign s (−1 forward).
fn turn(z: vec2<f32>, s: f32) -> vec2<f32> {
    return s * vec2<f32>(-z.y, z.x);
}

fn conj(z: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(z.x, -z.y);
}

struct Grid {
    // Padded columns and rows.
    px: u32,
    py: u32,
    // The frame's (or the kernel's) width and height.
    width: u32,
    height: u32,
    // Planes packed: 1 (imaginary part zero) or 2.
    planes: u32,
    // 1: a fraction per pixel is spread, else all of its light.
    fractions: u32,
    // 1: the multiply adds to what the target holds.
    accumulate: u32,
    // 1: the kernel's centre weight is left out of its spectrum.
    leave_centre: u32,
    // Which half of its packed kernel spectrum each plane takes: 0 the
    // real plane's, 1 the imaginary one's.
    half_a: u32,
    half_b: u32,
    // Centre weights applied exactly, per packed plane.
    centre: vec2<f32>,
    // 1/(px·py).
    scale: f32,
    // Lamps moved out of the frame's grid.
    lamps: u32,
    // Each plane's weight in the multiply.
    weights: vec2<f32>,
    // 1: the frame's planes came up as half floats, two to a word.
    halves_up: u32,
    // To 80 bytes, a whole number of the uniform layout's 16.
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
}

// Frame planes go up as f32, one to a word, or, where every value is a
// half float exactly, as halves, two to a word (value i in word i/2, the
// even one low): the same f32 either way. The word that holds value i:
fn word_of(i: u32, halves_up: u32) -> u32 {
    return select(i, i / 2u, halves_up == 1u);
}

// Value i from its word.
fn value_in(word: u32, i: u32, halves_up: u32) -> f32 {
    if halves_up == 1u {
        let pair = unpack2x16float(word);
        return select(pair.x, pair.y, (i & 1u) == 1u);
    }
    return bitcast<f32>(word);
}
