//! What one storage-buffer load costs on this device, by how its address varies across a SIMD group — the fact a
//! traversal design for lavapipe turns on (docs/profile-bvh.md). Each kernel runs chains of dependent vec4 loads
//! from a table of random words (16 MiB by default, larger than the caches like a big scene's BVH):
//! - `per_lane`: every lane follows its own random chain (what a ray per lane does: a gather);
//! - `uniform`: every lane of a workgroup follows the same chain (what a ray per subgroup, with lanes over a node's
//!   children, would do for its node loads);
//! - `consecutive`: a uniform chain whose lanes read eight neighbouring entries (lanes over a node's children);
//! - `alu`: the per-lane chain's arithmetic with the loads replaced by a hash (the loop's own cost);
//! - `per_lane_u64`: `per_lane` reading 32 bytes a load (vec4<u64>, on a device with 64-bit integers) from the same
//!   table: what shaders/geometry_loads_int64.wgsl turns on (a load's cost is per lane, not per byte).
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
    let entries = ["per_lane", "uniform", "consecutive", "alu", "per_lane_u64"];
    for entry in entries.into_iter().filter(|e| int64 || *e != "per_lane_u64") {
        let loads = if entry == "consecutive" { 2.0 } else { 1.0 } * STEPS as f64;
        let mut best = f64::MAX;
        for _ in 0..3 {
            let t0 = std::time::Instant::now();
            let job = ProbeJob {
                source: if entry == "per_lane_u64" { &u64_source } else { KERNELS },
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
