//! What one storage-buffer load costs on this device, by how its address varies across a SIMD group — the fact a
//! traversal design for lavapipe turns on (docs/profile-bvh.md). Each kernel runs chains of dependent vec4 loads
//! from a table of random words (16 MiB by default, larger than the caches like a big scene's BVH):
//! - `per_lane`: every lane follows its own random chain (what a ray per lane does: a gather);
//! - `uniform`: every lane of a workgroup follows the same chain (what a ray per subgroup, with lanes over a node's
//!   children, would do for its node loads);
//! - `consecutive`: a uniform chain whose lanes read eight neighbouring entries (lanes over a node's children);
//! - `alu`: the per-lane chain's arithmetic with the loads replaced by a hash (the loop's own cost);
//! - `per_lane_u64`: `per_lane` reading 32 bytes a load (vec4<u64>, on a device with 64-bit integers) from the same
//!   table: what shaders/geometry_loads_int64.wgsl turns on (a load's cost is per lane, not per byte);
//! - `per_lane_x4`, `uniform_x4`, `subgroup_x4`: four independent chains a lane (the loads' throughput, not one
//!   chain's latency), per lane, per workgroup, and per SIMD group through `subgroupBroadcastFirst` (an address the
//!   driver's divergence analysis can know to be the same in every lane: what a packet traversal would fetch).
//! `cargo run --release --example load_cost [LOG2_ENTRIES]` prints ns per load per lane for each, best of three dispatches.

use mislab::gpu::GpuContext;
use mislab::testkit::probe::{Probe, ProbeJob};

const STEPS: u32 = 512;
const WORKGROUPS: u32 = 512;
const WG_SIZE: u32 = 64;

const KERNELS: &str = r#"
@group(1) @binding(0) var<storage, read_write> out: array<u32>;
@group(1) @binding(1) var<storage, read> table: array<vec4<u32>>;
override MASK: u32 = 0xfffffu;
const STEPS: u32 = 512u;

fn hash(x: u32) -> u32 {
    var h = x * 747796405u + 2891336453u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    return (h >> 22u) ^ h;
}

@compute @workgroup_size(64)
fn per_lane(@builtin(global_invocation_id) g: vec3<u32>) {
    var a = hash(g.x);
    var acc = 0u;
    for (var i = 0u; i < STEPS; i++) {
        let v = table[a & MASK];
        acc += v.y + v.z + v.w;
        a = v.x ^ i;
    }
    out[g.x] = acc;
}

@compute @workgroup_size(64)
fn uniform(@builtin(workgroup_id) w: vec3<u32>, @builtin(global_invocation_id) g: vec3<u32>) {
    var a = hash(w.x);
    var acc = 0u;
    for (var i = 0u; i < STEPS; i++) {
        let v = table[a & MASK];
        acc += v.y + v.z + v.w;
        a = v.x ^ i;
    }
    out[g.x] = acc + g.x;
}

@compute @workgroup_size(64)
fn consecutive(@builtin(workgroup_id) w: vec3<u32>, @builtin(local_invocation_index) l: u32,
               @builtin(global_invocation_id) g: vec3<u32>) {
    var a = hash(w.x);
    var acc = 0u;
    for (var i = 0u; i < STEPS; i++) {
        let v = table[((a & MASK) & ~7u) | (l & 7u)];
        acc += v.y + v.z + v.w;
        // The chain continues from the uniform entry so that the next address stays uniform.
        a = table[a & MASK].x ^ i;
    }
    out[g.x] = acc;
}

@compute @workgroup_size(64)
fn alu(@builtin(global_invocation_id) g: vec3<u32>) {
    var a = hash(g.x);
    var acc = 0u;
    for (var i = 0u; i < STEPS; i++) {
        let h = hash(a & MASK);
        acc += h + (h >> 3u) + (h >> 7u);
        a = h ^ i;
    }
    out[g.x] = acc;
}
"#;

/// Four independent chains per lane (throughput rather than one chain's latency), 16 × STEPS loads in all: per lane, the
/// same in every lane of a workgroup, and per SIMD group (`subgroupBroadcastFirst`, which the driver's divergence
/// analysis can see is the same in every lane of the group).
const KERNELS_X4: &str = r#"
fn chains_x4(a0: u32, b0: u32, c0: u32, d0: u32) -> u32 {
    var a = a0; var b = b0; var c = c0; var d = d0;
    var acc = 0u;
    for (var i = 0u; i < STEPS * 4u; i++) {
        let va = table[a & MASK];
        let vb = table[b & MASK];
        let vc = table[c & MASK];
        let vd = table[d & MASK];
        acc += va.y + vb.z + vc.w + vd.y;
        a = va.x ^ i; b = vb.x ^ i; c = vc.x ^ i; d = vd.x ^ i;
    }
    return acc;
}

@compute @workgroup_size(64)
fn per_lane_x4(@builtin(global_invocation_id) g: vec3<u32>) {
    out[g.x] = chains_x4(hash(g.x), hash(g.x ^ 0x55555555u), hash(g.x + 0x1234567u), hash(g.x * 3u));
}

@compute @workgroup_size(64)
fn uniform_x4(@builtin(workgroup_id) w: vec3<u32>, @builtin(global_invocation_id) g: vec3<u32>) {
    out[g.x] = chains_x4(hash(w.x), hash(w.x ^ 0x55555555u), hash(w.x + 0x1234567u), hash(w.x * 3u)) + g.x;
}

@compute @workgroup_size(64)
fn subgroup_x4(@builtin(global_invocation_id) g: vec3<u32>) {
    let s = subgroupBroadcastFirst(g.x);
    out[g.x] = chains_x4(hash(s), hash(s ^ 0x55555555u), hash(s + 0x1234567u), hash(s * 3u)) + g.x;
}
"#;

/// `per_lane` over the same bytes as 32-byte elements (the u64 halves folded back to words), after KERNELS' header
/// with the table declared `array<vec4<u64>>` (`u64_source`).
const KERNEL_U64: &str = r#"
@compute @workgroup_size(64)
fn per_lane_u64(@builtin(global_invocation_id) g: vec3<u32>) {
    var a = hash(g.x);
    var acc = 0u;
    for (var i = 0u; i < STEPS; i++) {
        let w = table[(a & MASK) >> 1u];
        acc += u32(w.y) + u32(w.z) + u32(w.w >> 32u);
        a = u32(w.x) ^ i;
    }
    out[g.x] = acc;
}
"#;

fn main() {
    // The table: 2^k entries of 16 bytes (k = the first argument, default 20: 16 MiB; 14: 256 KiB fits a cache).
    let k: u32 = std::env::args().nth(1).map_or(20, |a| a.parse().expect("log2 of the table size"));
    let entries = 1u32 << k;
    let mask = [("MASK", (entries - 1) as f64)];
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("no GPU adapter: {e}"));
    println!("adapter: {}, table {} KiB", ctx.info.name, entries / 64);
    let mut words = Vec::with_capacity(4 * entries as usize);
    let mut s = 0x9e37_79b9u32;
    for _ in 0..4 * entries {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        words.push(s);
    }
    let table: &[u8] = bytemuck::cast_slice(&words);
    let lanes = (WORKGROUPS * WG_SIZE) as f64;
    let probe = Probe::new(&ctx);
    let int64 = ctx.device.features().contains(wgpu::Features::SHADER_INT64);
    if !int64 {
        println!("(no 64-bit integers on this device: per_lane_u64 not run)");
    }
    let header = &KERNELS[..KERNELS.find("@compute").expect("KERNELS has entry points")];
    let u64_source = header.replace("array<vec4<u32>>", "array<vec4<u64>>") + KERNEL_U64;
    let x4_source = header.to_string() + KERNELS_X4;
    let subgroups = ctx.device.features().contains(wgpu::Features::SUBGROUP);
    let entries =
        ["per_lane", "uniform", "consecutive", "alu", "per_lane_u64", "per_lane_x4", "uniform_x4", "subgroup_x4"];
    for entry in entries.into_iter().filter(|e| (int64 || *e != "per_lane_u64") && (subgroups || *e != "subgroup_x4")) {
        let loads = if entry == "consecutive" {
            2.0
        } else if entry.ends_with("_x4") {
            16.0
        } else {
            1.0
        } * STEPS as f64;
        let mut best = f64::MAX;
        for _ in 0..3 {
            let t0 = std::time::Instant::now();
            let job = ProbeJob {
                source: match entry {
                    "per_lane_u64" => &u64_source,
                    e if e.ends_with("_x4") => &x4_source,
                    _ => KERNELS,
                },
                entry,
                inputs: &[table],
                output_bytes: 4 * lanes as u64,
                workgroups: [WORKGROUPS, 1, 1],
                constants: &mask,
                geometry: None,
            };
            let out = probe.run(&job).unwrap_or_else(|e| panic!("{entry}: {e}"));
            assert!(out.iter().any(|&b| b != 0));
            best = best.min(t0.elapsed().as_secs_f64());
        }
        println!("{entry:>12}: {:7.2} ns per load per lane ({best:.3} s per dispatch)", best * 1e9 / (lanes * loads));
    }
}
