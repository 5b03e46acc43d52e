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

/// One sample of the pixel's radiance.
fn radiance(px: vec2<u32>, id: SampleId) -> vec3<f32> {
    var d = camera_direction(px, sample_2d(id, 0u));
    var o = params.cam_origin;
    rays_traced += 1u;
    var hit = trace_closest(o, d, F32_MAX);
    // The shading point at `hit`: shade() returns the next one with its continuation ray.
    var x = surface_at(hit, o, d);
    var l = vec3<f32>(0.0);
    var beta = vec3<f32>(1.0);
    let depth = select(min(params.max_depth, MAX_PATH_VERTICES), 1u, cfg_mode() == MODE_DIRECT);
    for (var bounce = 0u; bounce < depth; bounce += 1u) {
        if (hit.prim == INVALID) {
            // Only the camera ray adds the environment here; later vertices counted it in shade().
            if (bounce == 0u && params.env_light != INVALID) { l += env_eval(d); }
            break;
        }
        let m = scene_material(x.material);
        if (bounce == 0u && x.front) { l += material_emission(m, x.uv); }
        var c: ShadingCtx;
        c.x = x;
        c.frame = frame_from_normal(x.ns);
        c.wo = to_local(c.frame, -d);
        c.brdf = material_bsdf(m, x.uv);
        c.id = id;
        c.bounce = bounce;
        let want_next = bounce + 1u < depth;
        let s = shade(c, want_next);
        l += beta * s.radiance;
        if (!s.next_valid) { break; }
        beta *= s.next_weight;
        if (bounce + 1u >= params.rr_depth) {
            // Russian roulette: continue with probability max(β), at least 5%.
            let q = clamp(max(beta.x, max(beta.y, beta.z)), 0.05, 1.0);
            if (sample_1d(id, dim_base(bounce, 0u) + DIM_RR) >= q) { break; }
            beta /= q;
        }
        if (all(beta == vec3<f32>(0.0))) { break; }
        o = s.next_origin;
        d = s.next_dir;
        hit = s.next_hit;
        x = s.next_surface;
    }
    return l;
}

@compute @workgroup_size(8, 8, 1)
fn render_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    bvh_set_lane(lid);
    // The dispatch covers rows [row_offset, row_offset + row_count) of the film.
    let px = vec2<u32>(gid.x, gid.y + params.row_offset);
    if (px.x >= params.width || gid.y >= params.row_count || px.y >= params.height) { return; }
    let pixel = px.y * params.width + px.x;
    // Welford's update, one sample at a time: the mean moves by (x − mean)/n, a small correction, so it
    // stays accurate without a compensated (Kahan) sum — which lavapipe's reassociation would erase —
    // and the result does not depend on how samples are split into dispatches (bit-for-bit repeatable).
    var a = accum[pixel];
    var bad = 0u;
    for (var i = 0u; i < min(params.samples_per_dispatch, 65536u); i += 1u) {
        let id = SampleId(pixel, params.sample_base + i);
        let v = radiance(px, id);
        if (any_nonfinite3(v)) { bad += 1u; continue; }
        a.count += 1u;
        let delta = v - a.mean;
        a.mean += delta / f32(a.count);
        a.m2 += delta * (v - a.mean);
    }
    a.nonfinite += bad;
    accum[pixel] = a;
    if (bad > 0u) { atomicAdd(&counters[0], bad); }
    atomicAdd(&counters[1], rays_traced);
}
