// integrator.wgsl — the entry point: camera rays, the path loop (direct mode = one vertex), and the
// per-pixel accumulation of this dispatch's samples into the running mean / second moment.
//
// One trace per path vertex (as Mitsuba 3's path.cpp and pbrt-v4's PathIntegrator): the ray a vertex continues
// along is also its direction technique's sample, so the next trace finds the next vertex and the emission that
// sample counts (weighted by MIS against the light technique's pdf) at once. Camera rays, continuations and
// emission share one trace site — on lavapipe every call site's code runs whether or not a lane needs it.

const WORKGROUP: u32 = 8u;
/// Hard bound on path length whatever the settings say (lavapipe has no watchdog).
const MAX_PATH_VERTICES: u32 = 256u;

/// A camera ray through the point `jitter` (pixel units from the pixel's corner) of pixel px.
fn camera_direction(px: vec2<u32>, jitter: vec2<f32>) -> vec3<f32> {
    let film = (vec2<f32>(px) + jitter) / vec2<f32>(f32(params.width), f32(params.height));
    let x = (2.0 * film.x - 1.0) * params.tan_half_fov * params.aspect;
    let y = (1.0 - 2.0 * film.y) * params.tan_half_fov;
    return normalize(params.cam_forward + x * params.cam_right + y * params.cam_up);
}

/// A path between two vertices: the ray whose hit is its next vertex, and how to count the emission found there.
struct PathRay {
    id: SampleId,
    bounce: u32,              // the vertex this ray finds
    o: vec3<f32>,
    sample: DirectionSample,  // its direction w, and how the emission it finds is weighted
    emission_scale: f32,      // factor on the emission it finds (0: not a counted direction sample)
    beta: vec3<f32>,          // throughput, including f·cos/pdf of w
    l: vec3<f32>,             // radiance gathered so far
}

fn camera_ray(px: vec2<u32>, id: SampleId) -> PathRay {
    let filtered = filter_sample(sample_2d(id, 0u));
    let d = camera_direction(px, filtered.jitter);
    // The camera ray is no direction technique's sample: like a delta lobe's, its emission counts in full.
    let s = DirectionSample(params.cam_origin, vec3<f32>(0.0), false, d, 0.0, true, LightMeasure(MEASURE_NONE, 0.0));
    return PathRay(id, 0u, params.cam_origin, s, 1.0, vec3<f32>(filtered.weight), vec3<f32>(0.0));
}

/// Russian roulette's survival probability after a vertex whose scattering weight f·cos/pdf is `weight`: its
/// largest channel, at least 5 %. Not max(β) as in pbrt-v4 and Mitsuba 3: a survivor's β stays where it was when
/// roulette began instead of being lifted back to 1 (docs/estimators.md, "Russian roulette").
fn roulette_survival(weight: vec3<f32>) -> f32 {
    return clamp(max(weight.x, max(weight.y, weight.z)), 0.05, 1.0);
}

/// Traces the path's ray, counts the emission it finds, shades the vertex there and sets the next ray. Returns
/// false when the path has ended (its radiance is then complete in r.l). Vertices 0 .. depth − 1 are shaded;
/// the ray leaving the last one is traced only for the emission it finds.
fn path_vertex(r: ptr<function, PathRay>, depth: u32) -> bool {
    let ray = *r;
    // A path's last ray is traced only for the emission it finds: `trace_found` and `finds_no_emission` then cut it.
    let last = ray.bounce > 0u && ray.bounce >= depth;
    if (last && finds_no_emission(ray.o, ray.sample.w)) { return false; }
    let found = trace_found(ray.o, ray.sample, last);
    (*r).l += ray.beta * weighted_emission(ray.sample, found, ray.emission_scale);
    env_guide_learn_found(ray.sample, found);
    if (!found.at_surface || ray.bounce >= depth) { return false; }
    let x = found.surface;
    let c = shading_ctx(x, scene_material(x.material), ray.sample.w, ray.id, ray.bounce);
    let want_next = ray.bounce + 1u < depth;
    let s = shade(c, want_next);
    (*r).l += ray.beta * s.radiance;
    if (!s.next_valid) { return false; }
    var beta = ray.beta * s.next_weight;
    // Roulette is decided before the ray is traced: a surviving path counts what it finds with β/q (as pbrt-v4).
    if (want_next && ray.bounce + 1u >= params.rr_depth) {
        let q = roulette_survival(s.next_weight);
        if (sample_1d(c.id, dim_base(ray.bounce, 0u) + DIM_RR) >= q) { return false; }
        beta /= q;
    }
    if (all(beta == vec3<f32>(0.0))) { return false; }
    (*r).bounce = ray.bounce + 1u;
    (*r).o = s.next_origin;
    (*r).sample = s.next;
    (*r).emission_scale = s.next_scale;
    (*r).beta = beta;
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
fn render_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32,
               @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) lid3: vec3<u32>,
               @builtin(num_workgroups) groups: vec3<u32>) {
    bvh_set_lane(lid);
    // The dispatch covers rows [row_offset, row_offset + row_count) of the film; its workgroup rows take tile rows
    // in a spread order, so that each of lavapipe's threads (a static run of workgroups each) gets a fair share of
    // the image (src/render/tile_order.rs).
    let row = 8u * ((wg.y * max(params.tile_row_stride, 1u)) % groups.y) + lid3.y;
    let px = vec2<u32>(gid.x, row + params.row_offset);
    // Sample 0 of a guided render comes in two passes: the guide's learners, then the rest (env_guide.wgsl).
    if (px.x >= params.width || row >= params.row_count || px.y >= params.height || env_guide_skips(px)) { return; }
    let pixel = px.y * params.width + px.x;
    let n = min(params.samples_per_dispatch, 65536u);
    let depth = select(min(params.max_depth, MAX_PATH_VERTICES), 1u, cfg_mode() == MODE_DIRECT);
    var a = accum[pixel];
    var bad = 0u;
    if (cfg_mode() == MODE_PATH && (FLAT_SCENE || SPEC_MODE == MODE_PATH)) {
        // One loop over path vertices, not one per sample: a lane whose path ends starts its next sample at once,
        // instead of waiting for the longest path among its SIMD neighbours'. Only where the mode is fixed at compile
        // time for a BVH scene: a generic pipeline (the viewer's) would compile both loops, each with the whole
        // traversal inlined, and lavapipe takes minutes over that (docs/estimators.md, "One path loop").
        var ray = camera_ray(px, SampleId(pixel, params.sample_base));
        var started = 1u;
        var done = 0u;
        for (var it = 0u; it < n * (depth + 1u) && done < n; it += 1u) {
            if (path_vertex(&ray, depth)) { continue; }
            accumulate(&a, &bad, ray.l);
            done += 1u;
            if (started < n) {
                ray = camera_ray(px, SampleId(pixel, params.sample_base + started));
                started += 1u;
            }
        }
    } else {
        for (var i = 0u; i < n; i += 1u) {
            var ray = camera_ray(px, SampleId(pixel, params.sample_base + i));
            for (var k = 0u; k <= depth && path_vertex(&ray, depth); k += 1u) {}
            accumulate(&a, &bad, ray.l);
        }
    }
    // The environment guide's learning pass of a render resumed past its sample 0 only counts (`env_guide_learn_*`).
    if (params.guide_train == GUIDE_LEARN_ONLY) { return; }
    a.nonfinite += bad;
    accum[pixel] = a;
    if (bad > 0u) { atomicAdd(&counters[0], bad); }
    atomicAdd(&counters[1], rays_traced);
}
