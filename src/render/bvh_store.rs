//! Built BVHs kept across processes. A large scene's wide BVH takes seconds to build (the dining room's 270k
//! triangles: 2.0 s, the living room's 143k: 0.9 s) and was built again by every run, where the driver's compiled
//! pipelines are already kept (`gpu::pipeline_store`): a repeated render's start-up was mostly this.
//!
//! One file per build input in the cache directory's `bvh/` (`io::cache_file::cache_dir`), named by a 64-bit hash
//! of everything the build reads — the triangles, spheres and quads as bytes, the pre-split choice — and of the
//! builder itself (its source files and `Cargo.lock`, which pins obvhs, compiled into the binary). A changed scene
//! or a changed builder is a miss, never a stale hit; the file also repeats the input counts and the key, checked
//! on load. The frame's length and CRC-32 (`io::cache_file`) find a damaged file, and a loaded tree is checked to
//! reference only nodes and primitives that exist before it is used; a file that fails either is reported, ignored
//! and rewritten. Files are written through a private temporary file and renamed (concurrent runs see one whole
//! file or the other). The folder is bounded: past [`MAX_BYTES`] the least recently written files are removed.
//! Scenes under [`MIN_PRIMS`] primitives build in under ~0.1 s and are not stored.

use crate::accel::bvh::{Bvh, Presplit};
use crate::accel::wide_bvh::{self, GpuWideNode};
use crate::accel::wide_node::{WideChild, WIDTH};
use crate::gpu::types::{GpuQuad, GpuSphere, PRIM_INDEX_MASK, PRIM_KIND_SHIFT, PRIM_QUAD, PRIM_SPHERE, PRIM_TRIANGLE};
use crate::io::cache_file;
use glam::Vec3;
use std::path::{Path, PathBuf};

/// A stored BVH file's first bytes, with its format's version.
const MAGIC: &[u8; 8] = b"MISLBV01";
/// Fewest primitives (triangles + spheres + quads) whose BVH is stored.
pub const MIN_PRIMS: usize = 16_384;
/// The folder's bound: past it, the least recently written files go.
pub const MAX_BYTES: u64 = 512 << 20;

/// The builder's code, as compiled into this binary: any change to it changes every key.
const BUILDER_SOURCES: [&[u8]; 7] = [
    include_bytes!("../accel/bvh.rs"),
    include_bytes!("../accel/wide_bvh.rs"),
    include_bytes!("../accel/wide_node.rs"),
    include_bytes!("../accel/presplit.rs"),
    include_bytes!("../accel/quantise.rs"),
    include_bytes!("../accel/aabb.rs"),
    include_bytes!("../../Cargo.lock"),
];

/// `wide_bvh::build`, through the store in the cache directory (where there is one and the scene is large enough).
pub fn build(tris: &[[Vec3; 3]], spheres: &[GpuSphere], quads: &[GpuQuad], presplit: Presplit) -> Bvh {
    let dir = cache_file::cache_dir().map(|d| d.join("bvh"));
    match dir {
        Some(dir) if tris.len() + spheres.len() + quads.len() >= MIN_PRIMS => {
            build_in(&dir, tris, spheres, quads, presplit).0
        }
        _ => wide_bvh::build(tris, spheres, quads, presplit),
    }
}

/// Where a BVH came from (`build_in`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// Read from the store.
    Loaded,
    /// Built (and stored, unless writing failed, which was warned of).
    Built,
    /// Built because the stored file could not be used (warned of), and stored afresh.
    Rebuilt(String),
}

/// `wide_bvh::build` through the store in `dir`, whatever the scene's size; says where the tree came from.
pub fn build_in(
    dir: &Path,
    tris: &[[Vec3; 3]],
    spheres: &[GpuSphere],
    quads: &[GpuQuad],
    presplit: Presplit,
) -> (Bvh, Origin) {
    let counts = [tris.len() as u64, spheres.len() as u64, quads.len() as u64];
    let key = key(tris, spheres, quads, &presplit);
    let path = file_for(dir, key);
    let start = web_time::Instant::now();
    let mut origin = Origin::Built;
    if let Ok(bytes) = std::fs::read(&path) {
        match cache_file::unframe(MAGIC, &bytes).and_then(|data| decode(data, key, counts)) {
            Ok(mut bvh) => {
                bvh.build_seconds = start.elapsed().as_secs_f64();
                return (bvh, Origin::Loaded);
            }
            Err(why) => {
                eprintln!("warning: stored BVH {}: {why}; built again", path.display());
                origin = Origin::Rebuilt(why.to_string());
            }
        }
    }
    let bvh = wide_bvh::build(tris, spheres, quads, presplit);
    if !bvh.wide.is_empty() {
        let written = cache_file::write_atomically(&path, &cache_file::frame(MAGIC, &encode(&bvh, key, counts)));
        match written {
            Ok(()) => cache_file::evict(dir, "bvh", MAX_BYTES, &path),
            Err(e) => eprintln!("warning: BVH store {}: not saved ({e})", path.display()),
        }
    }
    (bvh, origin)
}

/// The file for `key` in `dir`.
pub fn file_for(dir: &Path, key: u64) -> PathBuf {
    dir.join(format!("{key:016x}.bvh"))
}

/// A 64-bit FNV-1a over 8-byte words (fast enough for millions of vertices), seeded with the builder's code.
struct Hasher(u64);

impl Hasher {
    fn bytes(&mut self, b: &[u8]) {
        self.0 = (self.0 ^ b.len() as u64).wrapping_mul(0x0000_0100_0000_01b3);
        let mut words = b.chunks_exact(8);
        for w in &mut words {
            self.0 = (self.0 ^ u64::from_le_bytes(w.try_into().unwrap())).wrapping_mul(0x0000_0100_0000_01b3);
        }
        for &r in words.remainder() {
            self.0 = (self.0 ^ r as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// The key of a build: its inputs and the builder's code.
pub fn key(tris: &[[Vec3; 3]], spheres: &[GpuSphere], quads: &[GpuQuad], presplit: &Presplit) -> u64 {
    let mut h = Hasher(0xcbf2_9ce4_8422_2325);
    for s in BUILDER_SOURCES {
        h.bytes(s);
    }
    h.bytes(bytemuck::cast_slice(tris));
    h.bytes(bytemuck::cast_slice(spheres));
    h.bytes(bytemuck::cast_slice(quads));
    match presplit {
        Presplit::Off => h.bytes(b"off"),
        Presplit::Large { keep_whole } => {
            h.bytes(b"large");
            let bits: Vec<u8> = keep_whole.iter().map(|&k| k as u8).collect();
            h.bytes(&bits);
        }
    }
    h.0
}

fn encode(bvh: &Bvh, key: u64, counts: [u64; 3]) -> Vec<u8> {
    let mut out = Vec::new();
    for w in [key, counts[0], counts[1], counts[2]] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    out.extend_from_slice(&bvh.sah_cost.to_le_bytes());
    out.extend_from_slice(&(bvh.prim_refs.len() as u64).to_le_bytes());
    out.extend_from_slice(bytemuck::cast_slice(&bvh.prim_refs));
    out.extend_from_slice(&(bvh.wide.len() as u64).to_le_bytes());
    out.extend_from_slice(bytemuck::cast_slice(&bvh.wide));
    out
}

/// Reads `data` back into a wide BVH (its BVH2 `nodes` the one empty root, as `wide_bvh::widen` leaves them),
/// refusing one of another key or input, or one that references what does not exist.
fn decode(data: &[u8], key: u64, counts: [u64; 3]) -> Result<Bvh, &'static str> {
    let mut at = 0usize;
    let mut take = |n: usize| -> Result<&[u8], &'static str> {
        let s = data.get(at..at.checked_add(n).ok_or("too short")?).ok_or("too short")?;
        at += n;
        Ok(s)
    };
    let mut word = || take(8).map(|b| u64::from_le_bytes(b.try_into().unwrap()));
    if word()? != key || [word()?, word()?, word()?] != counts {
        return Err("of another scene");
    }
    let sah_cost = f32::from_le_bytes(take(4)?.try_into().unwrap());
    let n_refs = usize::try_from(u64::from_le_bytes(take(8)?.try_into().unwrap())).map_err(|_| "too short")?;
    let prim_refs: Vec<u32> = bytemuck::pod_collect_to_vec(take(n_refs.checked_mul(4).ok_or("too short")?)?);
    let n_wide = usize::try_from(u64::from_le_bytes(take(8)?.try_into().unwrap())).map_err(|_| "too short")?;
    let size = std::mem::size_of::<GpuWideNode>();
    let wide: Vec<GpuWideNode> = bytemuck::pod_collect_to_vec(take(n_wide.checked_mul(size).ok_or("too short")?)?);
    if at != data.len() {
        return Err("longer than its contents");
    }
    check(&prim_refs, &wide, counts)?;
    Ok(Bvh { nodes: vec![wide_bvh::empty_bvh2_root()], prim_refs, wide, build_seconds: 0.0, sah_cost })
}

/// Whether every child index is a node, every leaf range inside `prim_refs`, and every reference a primitive.
fn check(prim_refs: &[u32], wide: &[GpuWideNode], counts: [u64; 3]) -> Result<(), &'static str> {
    if wide.is_empty() {
        return Err("empty");
    }
    for node in wide {
        for slot in 0..WIDTH {
            match node.child(slot) {
                WideChild::Interior(c) if c as usize >= wide.len() => return Err("a child beyond the nodes"),
                WideChild::Leaf { first, count } if (first + count) as usize > prim_refs.len() => {
                    return Err("a leaf beyond the references")
                }
                _ => {}
            }
        }
    }
    for &r in prim_refs {
        let n = match r >> PRIM_KIND_SHIFT {
            PRIM_TRIANGLE => counts[0],
            PRIM_SPHERE => counts[1],
            PRIM_QUAD => counts[2],
            _ => 0,
        };
        if (r & PRIM_INDEX_MASK) as u64 >= n {
            return Err("a reference beyond the primitives");
        }
    }
    Ok(())
}
