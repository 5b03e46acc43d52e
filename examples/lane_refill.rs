//! Does refilling a lane with its next ray inside one traversal loop (Aila & Laine 2009's persistent threads, the
//! main device-side gain of a wavefront design) beat tracing the same rays one traversal at a time? Each lane traces
//! 4, then 20 rays either way; the difference gives ns per ray. `probe_stream` is shaders/bvh_wide.wgsl's
//! `wide_traverse` loop with that refill added (kept here, not in the product: it measured no gain on lavapipe,
//! docs/profile-bvh.md "Lanes refilled inside the traversal").
//! `cargo run --release --example lane_refill [SCENE.glb|.gltf|.toml] [RAYS]` (default: DamagedHelmet, 65,536 rays)

use mislab::accel::bvh;
use mislab::gpu::GpuContext;
use mislab::testkit::probe::{GeometryBuffers, Probe};
use std::time::Instant;

#[path = "common/rays.rs"]
mod rays;

const KERNEL: &str = "
override STREAM: u32 = 1u;
override ANY: bool = false;
fn stream_ray(i: u32, k: u32) -> ProbeRay {
    return probe_in[(i + k * 104729u) % PROBE_COUNT];
}
fn probe_seq(r0: ProbeRay) -> u32 {
    let i = bitcast<u32>(r0._pad);
    var acc = 0u;
    for (var k = 0u; k < STREAM; k++) {
        let q = stream_ray(i, k);
        if ANY {
            acc += select(0u, 1u, trace_any(q.o, q.d, q.t_max));
        } else {
            acc += trace_closest(q.o, q.d, q.t_max).prim;
        }
    }
    return acc;
}
fn probe_stream(r0: ProbeRay) -> u32 {
    let i = bitcast<u32>(r0._pad);
    var acc = 0u;
    var k = 0u;
    let base = bvh_lane * BVH_STACK_SIZE;
    var q = stream_ray(i, 0u);
    var r = trace_ray_setup(q.o, q.d);
    var hit = Hit(q.t_max, INVALID, 0.0, 0.0);
    var oct = select(0u, 1u, r.d.x < 0.0) | select(0u, 2u, r.d.y < 0.0) | select(0u, 4u, r.d.z < 0.0);
    var g = vec2<u32>(0u, 1u << (24u + oct));
    var tg = vec2<u32>(0u, 0u);
    var sp = 0u;
    var top = vec2<u32>(0u, 0u);
    var top_full = false;
    let bound = (3u * wide_node_count() + 1u) * STREAM;
    for (var round = 0u; round < bound && k < STREAM; round++) {
        for (var step = 0u; step < bound && tg.y == 0u && ((g.y & WIDE_NODE_BITS) != 0u || sp > 0u || top_full); step++) {
            if (g.y & WIDE_NODE_BITS) == 0u {
                var e = top;
                if top_full {
                    top_full = false;
                } else {
                    sp -= 1u;
                    e = bvh_stack[base + sp];
                }
                if (e.y & WIDE_NODE_BITS) != 0u {
                    g = e;
                } else {
                    tg = e;
                }
            }
            if (g.y & WIDE_NODE_BITS) != 0u {
                let bit = countTrailingZeros(g.y & WIDE_NODE_BITS);
                let slot = (bit - 24u) ^ oct;
                let idx = g.x + countOneBits(g.y & ((1u << slot) - 1u));
                g.y &= ~(1u << bit);
                if (g.y & WIDE_NODE_BITS) != 0u {
                    if top_full {
                        wide_push(base, &sp, top);
                    }
                    top = g;
                    top_full = true;
                }
                let node = wide_node(idx);
                let hits = wide_node_hits(r, oct, node, hit.t);
                g = vec2<u32>(node.links.x, (hits & WIDE_NODE_BITS) | (node.head.w >> 24u));
                tg = vec2<u32>(node.links.y, hits & ~WIDE_NODE_BITS);
            }
        }
        for (var j = 0u; j < 24u && tg.y != 0u; j++) {
            let lh = bvh_leaf_test(r, tg.x + countTrailingZeros(tg.y), hit.t, INVALID);
            tg.y &= tg.y - 1u;
            if lh.h.w != 0.0 {
                hit = Hit(lh.h.x, lh.prim, lh.h.y, lh.h.z);
                if ANY {
                    tg.y = 0u;
                    g.y = 0u;
                    sp = 0u;
                    top_full = false;
                }
            }
        }
        if (g.y & WIDE_NODE_BITS) == 0u && tg.y == 0u && sp == 0u && !top_full {
            if ANY {
                acc += select(0u, 1u, hit.prim != INVALID);
            } else {
                acc += hit.prim;
            }
            k += 1u;
            if k < STREAM {
                q = stream_ray(i, k);
                r = trace_ray_setup(q.o, q.d);
                hit = Hit(q.t_max, INVALID, 0.0, 0.0);
                oct = select(0u, 1u, r.d.x < 0.0) | select(0u, 2u, r.d.y < 0.0) | select(0u, 4u, r.d.z < 0.0);
                g = vec2<u32>(0u, 1u << (24u + oct));
            }
        }
    }
    return acc;
}
";

fn main() {
    let path = std::env::args().nth(1).unwrap_or(rays::HELMET.to_string());
    let n: usize = std::env::args().nth(2).map(|s| s.parse().expect("RAYS")).unwrap_or(1 << 16);
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("{e}"));
    let tris = rays::triangles(&path);
    let wide = mislab::accel::wide_bvh::build(&tris, &[], &[], bvh::Presplit::Large { keep_whole: &[] });
    let geo = GeometryBuffers::new(&ctx, &wide, &tris, &[], &[]);
    let library = mislab::testkit::probe::trace_module(KERNEL)
        .replace("override WIDE_BVH: bool = false;", "override WIDE_BVH: bool = true;");
    let probe = Probe::new(&ctx);
    let rays = rays::bounce_rays(&tris, n, false);
    println!("{} triangles, {} rays", tris.len(), rays.len());
    for any in [false, true] {
        let lib = library.replace("override ANY: bool = false;", &format!("override ANY: bool = {any};"));
        let src =
            |stream: u32| lib.replace("override STREAM: u32 = 1u;", &format!("override STREAM: u32 = {stream}u;"));
        let (lo, hi) = (src(4), src(20));
        let mut best = [f64::MAX; 2];
        let mut agree = 0;
        for _round in 0..3 {
            let mut outs = Vec::new();
            for (v, function) in ["probe_seq", "probe_stream"].into_iter().enumerate() {
                let mut t = [0.0; 2];
                for (j, s) in [&lo, &hi].into_iter().enumerate() {
                    let t0 = Instant::now();
                    let out: Vec<u32> =
                        probe.map(s, "ProbeRay", "u32", function, &rays, Some(&geo)).unwrap_or_else(|e| panic!("{e}"));
                    t[j] = t0.elapsed().as_secs_f64();
                    if j == 1 {
                        outs.push(out);
                    }
                }
                best[v] = best[v].min((t[1] - t[0]) / (16.0 * rays.len() as f64) * 1e9);
            }
            agree = outs[0].iter().zip(&outs[1]).filter(|(a, b)| a == b).count();
        }
        println!(
            "any={any}: one traversal a ray {:.1} ns per ray, refilled lanes {:.1} ns ({:.2}x); {:.2} % of lanes' sums agree",
            best[0],
            best[1],
            best[1] / best[0],
            100.0 * agree as f64 / rays.len() as f64
        );
    }
}
