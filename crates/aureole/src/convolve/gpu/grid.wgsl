@group(0) @binding(0) var<uniform> grid: Grid;
@group(0) @binding(1) var<storage, read> planes: array<u32>;
@group(0) @binding(2) var<storage, read> fractions: array<f32>;
@group(0) @binding(3) var<storage, read_write> packed: array<vec2<f32>>;

fn value(i: u32, halves_up: u32) -> f32 {
    return value_in(planes[word_of(i, halves_up)], i, halves_up);
}

// The bright parts of one or two frame planes, packed as real and
// imaginary parts into the first `height` rows of the grid.
@compute @workgroup_size(64)
fn load(@builtin(global_invocation_id) id: vec3<u32>) {
    let x = id.x;
    let y = id.y;
    if x >= grid.px || y >= grid.height {
        return;
    }
    var z = vec2<f32>(0.0, 0.0);
    if x < grid.width {
        let i = y * grid.width + x;
        var f = 1.0;
        if grid.fractions == 1u {
            f = fractions[i];
        }
        z.x = value(i, grid.halves_up) * f;
        if grid.planes == 2u {
            z.y = value(grid.width * grid.height + i, grid.halves_up) * f;
        }
    }
    packed[y * grid.px + x] = z;
}

// One or two kernel planes (`width` × `height`, centre at the middle)
// packed into the whole grid, their centre at (0, 0) and the rest wrapped
// around.
@compute @workgroup_size(64)
fn place(@builtin(global_invocation_id) id: vec3<u32>) {
    let u = id.x;
    let v = id.y;
    if u >= grid.px || v >= grid.py {
        return;
    }
    let i = (u + grid.width / 2u) % grid.px;
    let j = (v + grid.height / 2u) % grid.py;
    var z = vec2<f32>(0.0, 0.0);
    let centre = u == 0u && v == 0u && grid.leave_centre == 1u;
    if i < grid.width && j < grid.height && !centre {
        let at = j * grid.width + i;
        z.x = value(at, 0u);
        if grid.planes == 2u {
            z.y = value(grid.width * grid.height + at, 0u);
        }
    }
    packed[v * grid.px + u] = z;
}

