// needs: types
// gather_reach: per tile_size^2 tile, the largest radius among its pixels whose input
// flux is non-zero, 0 if none (core/src/kernels/gather_reach.rs). Mirror of
// backend-opencl/kernels/gather_reach.cl and backend-cpu/src/kernels/density_gather.rs.

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var<storage, read> radius: array<f32>;
@group(0) @binding(2) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> tiles: array<f32>;

fn gather_reach(t: u32) {
    let p = params;
    let w = p.camera.width;
    let h = p.camera.height;
    let ts = p.tile_size;
    let tw = (w + ts - 1u) / ts;
    let th = (h + ts - 1u) / ts;
    if (t >= tw * th) {
        return;
    }
    let tx = t % tw;
    let ty = t / tw;
    var r = 0.0;
    for (var y = ty * ts; y < min((ty + 1u) * ts, h); y++) {
        for (var x = tx * ts; x < min((tx + 1u) * ts, w); x++) {
            let i = y * w + x;
            let s = input[i];
            if (s.x != 0.0 || s.y != 0.0 || s.z != 0.0) {
                r = max(r, radius[i]);
            }
        }
    }
    tiles[t] = r;
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    gather_reach(i);
}
