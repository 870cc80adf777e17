@group(0) @binding(0) var<uniform> output: Grid;
@group(0) @binding(1) var<storage, read> frame: array<u32>;
@group(0) @binding(2) var<storage, read> shares: array<f32>;
@group(0) @binding(3) var<storage, read> convolved: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read_write> result: array<f32>;

fn value(i: u32) -> f32 {
    return value_in(frame[word_of(i, output.halves_up)], i, output.halves_up);
}

// Each output pixel: the moved light, the centre's share of the bright
// part, and the light that stays, as the CPU engine's rows finish.
@compute @workgroup_size(64)
fn finish(@builtin(global_invocation_id) id: vec3<u32>) {
    let x = id.x;
    let y = id.y;
    if x >= output.width || y >= output.height {
        return;
    }
    let i = y * output.width + x;
    let c = convolved[y * output.px + x];
    var f = 1.0;
    if output.fractions == 1u {
        f = shares[i];
    }
    let n = output.width * output.height;
    let s0 = value(i);
    let bright0 = s0 * f;
    result[i] = c.x * output.scale + output.centre.x * bright0 + (s0 - bright0);
    if output.planes == 2u {
        let s1 = value(n + i);
        let bright1 = s1 * f;
        result[n + i] = c.y * output.scale + output.centre.y * bright1 + (s1 - bright1);
    }
}
