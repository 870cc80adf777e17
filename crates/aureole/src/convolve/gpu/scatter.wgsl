@group(0) @binding(0) var<uniform> moving: Grid;
@group(0) @binding(1) var<storage, read> lamps: array<u32>;
@group(0) @binding(2) var<storage, read_write> rest: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> lit: array<vec2<f32>>;

// The lamps' bright parts (row-major frame indices) moved from the loaded
// grid into a grid of their own, zeros elsewhere: the two bands the
// transforms take apart.
@compute @workgroup_size(64)
fn scatter(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= moving.lamps {
        return;
    }
    let i = lamps[id.x];
    let at = (i / moving.width) * moving.px + i % moving.width;
    lit[at] = rest[at];
    rest[at] = vec2<f32>(0.0, 0.0);
}
