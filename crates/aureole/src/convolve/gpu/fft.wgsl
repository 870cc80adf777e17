struct Pass {
    // Transform length.
    n: u32,
    // Product of the radices of the passes before this one.
    ns: u32,
    // Distance between a transform's elements.
    stride: u32,
    // Distance between transforms.
    batch_stride: u32,
    // Transforms.
    batch: u32,
    // Where this length's twiddles start in the table.
    twiddles: u32,
    // 1: the inverse transform (e^{+i}).
    inverse: u32,
    // 1: invocations along x run over transforms (columns: neighbours in
    // memory), else over a transform's butterflies (rows).
    columns: u32,
}

@group(0) @binding(0) var<uniform> step: Pass;
@group(0) @binding(1) var<storage, read> source: array<vec2<f32>>;
@group(0) @binding(2) var<storage, read_write> sink: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read> table: array<vec2<f32>>;

override RADIX: u32 = 2u;

@compute @workgroup_size(64)
fn stockham(@builtin(global_invocation_id) id: vec3<u32>) {
    var j: u32;
    var b: u32;
    if step.columns == 1u {
        b = id.x;
        j = id.y;
    } else {
        j = id.x;
        b = id.y;
    }
    let m = step.n / RADIX;
    if j >= m || b >= step.batch {
        return;
    }
    let base = b * step.batch_stride;
    let k = j % step.ns;
    let stride = step.n / (step.ns * RADIX);
    let s = select(-1.0, 1.0, step.inverse == 1u);
    var v: array<vec2<f32>, 5>;
    for (var r = 0u; r < RADIX; r++) {
        var t = table[step.twiddles + k * r * stride];
        if step.inverse == 1u {
            t.y = -t.y;
        }
        v[r] = mul(source[base + (j + r * m) * step.stride], t);
    }
    var y: array<vec2<f32>, 5>;
    switch RADIX {
        case 2u: {
            y[0] = v[0] + v[1];
            y[1] = v[0] - v[1];
        }
        case 3u: {
            let sum = v[1] + v[2];
            let t = v[0] - 0.5 * sum;
            let u = turn(v[1] - v[2], s * 0.86602540378443864676);
            y[0] = v[0] + sum;
            y[1] = t + u;
            y[2] = t - u;
        }
        case 4u: {
            let t0 = v[0] + v[2];
            let t1 = v[0] - v[2];
            let t2 = v[1] + v[3];
            let t3 = turn(v[1] - v[3], s);
            y[0] = t0 + t2;
            y[1] = t1 + t3;
            y[2] = t0 - t2;
            y[3] = t1 - t3;
        }
        default: {
            let c1 = 0.30901699437494742410;
            let c2 = -0.80901699437494742410;
            let s1 = 0.95105651629515357212;
            let s2 = 0.58778525229247312917;
            let b1 = v[1] + v[4];
            let b2 = v[2] + v[3];
            let d1 = v[1] - v[4];
            let d2 = v[2] - v[3];
            let t1 = v[0] + c1 * b1 + c2 * b2;
            let t2 = v[0] + c2 * b1 + c1 * b2;
            let u1 = turn(s1 * d1 + s2 * d2, s);
            let u2 = turn(s2 * d1 - s1 * d2, s);
            y[0] = v[0] + b1 + b2;
            y[1] = t1 + u1;
            y[4] = t1 - u1;
            y[2] = t2 + u2;
            y[3] = t2 - u2;
        }
    }
    let d = (j / step.ns) * step.ns * RADIX + k;
    for (var r = 0u; r < RADIX; r++) {
        sink[base + (d + r * step.ns) * step.stride] = y[r];
    }
}
