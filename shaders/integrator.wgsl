// integrator.wgsl — the entry point: camera rays, the path loop (direct mode = one vertex), and the
// per-pixel accumulation of this dispatch's samples into the running mean / second moment.

const WORKGROUP: u32 = 8u;
/// Hard bound on path length whatever the settings say (lavapipe has no watchdog).
const MAX_PATH_VERTICES: u32 = 256u;

/// A camera ray through the pixel with a box-filter jitter.
fn camera_direction(px: vec2<u32>, jitter: vec2<f32>) -> vec3<f32> {
    let film = (vec2<f32>(px) + jitter) / vec2<f32>(f32(params.width), f32(params.height));
    let x = (2.0 * film.x - 1.0) * params.tan_half_fov * params.aspect;
    let y = (1.0 - 2.0 * film.y) * params.tan_half_fov;
    return normalize(params.cam_forward + x * params.cam_right + y * params.cam_up);
}

/// A path in flight: its sample, the vertex it is at, the ray that found that vertex, and what it carries.
struct Path {
    id: SampleId,
    bounce: u32,
    d: vec3<f32>,
    hit: Hit,
    x: Surface,
    l: vec3<f32>,
    beta: vec3<f32>,
}

/// Starts a sample: the camera ray through the pixel, traced.
fn start_path(px: vec2<u32>, id: SampleId) -> Path {
    var p: Path;
    p.id = id;
    p.bounce = 0u;
    p.d = camera_direction(px, sample_2d(id, 0u));
    rays_traced += 1u;
    p.hit = trace_closest(params.cam_origin, p.d, F32_MAX);
    // The shading point at `hit`: shade() returns the next one with its continuation ray.
    p.x = surface_at(p.hit, params.cam_origin, p.d);
    p.l = vec3<f32>(0.0);
    p.beta = vec3<f32>(1.0);
    return p;
}

/// Shades the path's vertex and moves it to the next one. Returns false when the path has ended (its radiance
/// is then complete in p.l).
fn path_step(p: ptr<function, Path>, depth: u32) -> bool {
    let bounce = (*p).bounce;
    if ((*p).hit.prim == INVALID) {
        // Only the camera ray adds the environment here; later vertices counted it in shade().
        if (bounce == 0u && params.env_light != INVALID) { (*p).l += env_eval((*p).d); }
        return false;
    }
    let x = (*p).x;
    let m = scene_material(x.material);
    if (bounce == 0u && x.front) { (*p).l += material_emission(m, x.uv); }
    var c: ShadingCtx;
    c.x = x;
    c.frame = frame_from_normal(x.ns);
    c.wo = to_local(c.frame, -(*p).d);
    c.brdf = material_bsdf(m, x.uv);
    c.id = (*p).id;
    c.bounce = bounce;
    let want_next = bounce + 1u < depth;
    let s = shade(c, want_next);
    (*p).l += (*p).beta * s.radiance;
    if (!s.next_valid) { return false; }
    var beta = (*p).beta * s.next_weight;
    if (bounce + 1u >= params.rr_depth) {
        // Russian roulette: continue with probability max(β), at least 5%.
        let q = clamp(max(beta.x, max(beta.y, beta.z)), 0.05, 1.0);
        if (sample_1d(c.id, dim_base(bounce, 0u) + DIM_RR) >= q) { return false; }
        beta /= q;
    }
    if (all(beta == vec3<f32>(0.0))) { return false; }
    (*p).beta = beta;
    (*p).bounce = bounce + 1u;
    (*p).d = s.next_dir;
    (*p).hit = s.next_hit;
    (*p).x = s.next_surface;
    return true;
}

/// Welford's update, one sample at a time: the mean moves by (x − mean)/n, a small correction, so it stays accurate
/// without a compensated (Kahan) sum — which lavapipe's reassociation would erase — and the result does not depend
/// on how samples are split into dispatches (bit-for-bit repeatable). Non-finite samples are counted, not added.
fn accumulate(a: ptr<function, Accum>, bad: ptr<function, u32>, v: vec3<f32>) {
    if (any_nonfinite3(v)) {
        *bad += 1u;
        return;
    }
    (*a).count += 1u;
    let delta = v - (*a).mean;
    (*a).mean += delta / f32((*a).count);
    (*a).m2 += delta * (v - (*a).mean);
}

@compute @workgroup_size(8, 8, 1)
fn render_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    bvh_set_lane(lid);
    // The dispatch covers rows [row_offset, row_offset + row_count) of the film.
    let px = vec2<u32>(gid.x, gid.y + params.row_offset);
    if (px.x >= params.width || gid.y >= params.row_count || px.y >= params.height) { return; }
    let pixel = px.y * params.width + px.x;
    let n = min(params.samples_per_dispatch, 65536u);
    let depth = select(min(params.max_depth, MAX_PATH_VERTICES), 1u, cfg_mode() == MODE_DIRECT);
    var a = accum[pixel];
    var bad = 0u;
    if (FLAT_SCENE) {
        // One loop over path vertices, not one per sample: a lane whose path ends starts its next sample at
        // once. lavapipe runs a loop's SIMD lanes until the last one is done, so with a loop per sample every
        // lane waited for the longest path among its neighbours'. (With a BVH, lanes that restart at different
        // times would walk the tree apart, so BVH scenes keep the loop per sample below.)
        var path = start_path(px, SampleId(pixel, params.sample_base));
        var started = 1u;
        var done = 0u;
        for (var it = 0u; it < n * (depth + 1u) && done < n; it += 1u) {
            if (path_step(&path, depth)) { continue; }
            accumulate(&a, &bad, path.l);
            done += 1u;
            if (started < n) {
                path = start_path(px, SampleId(pixel, params.sample_base + started));
                started += 1u;
            }
        }
    } else {
        for (var i = 0u; i < n; i += 1u) {
            var path = start_path(px, SampleId(pixel, params.sample_base + i));
            for (var k = 0u; k < depth && path_step(&path, depth); k += 1u) {}
            accumulate(&a, &bad, path.l);
        }
    }
    a.nonfinite += bad;
    accum[pixel] = a;
    if (bad > 0u) { atomicAdd(&counters[0], bad); }
    atomicAdd(&counters[1], rays_traced);
}
