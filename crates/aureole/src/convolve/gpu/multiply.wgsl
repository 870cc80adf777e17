@group(0) @binding(0) var<uniform> product: Grid;
@group(0) @binding(1) var<storage, read> frames: array<vec2<f32>>;
@group(0) @binding(2) var<storage, read> kernels_a: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read> kernels_b: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read_write> products: array<vec2<f32>>;

// The spectrum of the real plane packed as the real (half 0) or the
// imaginary part (half 1) of z: (Z(k) + Z*(−k))/2 or (Z(k) − Z*(−k))/2i.
fn half(z: vec2<f32>, mirrored: vec2<f32>, which: u32) -> vec2<f32> {
    let zm = conj(mirrored);
    if which == 0u {
        return 0.5 * (z + zm);
    }
    return turn(z - zm, -0.5);
}

// With a = Re z and b = Im z real planes, A·Ka + i·B·Kb transforms back to
// a⊛ka + i·b⊛kb: two planes through one complex transform each way.
@compute @workgroup_size(64)
fn multiply(@builtin(global_invocation_id) id: vec3<u32>) {
    let u = id.x;
    let v = id.y;
    if u >= product.px || v >= product.py {
        return;
    }
    let i = v * product.px + u;
    let mirrored = ((product.py - v) % product.py) * product.px + (product.px - u) % product.px;
    let a = half(frames[i], frames[mirrored], 0u);
    let b = half(frames[i], frames[mirrored], 1u);
    let ka = product.weights.x * half(kernels_a[i], kernels_a[mirrored], product.half_a);
    let kb = product.weights.y * half(kernels_b[i], kernels_b[mirrored], product.half_b);
    var w = mul(a, ka) + turn(mul(b, kb), 1.0);
    if product.accumulate == 1u {
        w += products[i];
    }
    products[i] = w;
}
