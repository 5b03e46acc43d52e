//! Built BVHs kept across processes (src/render/bvh_store.rs): a stored tree reads back equal to the build, a
//! damaged or foreign file is refused and rebuilt, another input is another file, and the folder stays bounded.
//! CPU only, in private temporary folders.

mod common;

use common::{rect, uv_sphere};
use glam::Vec3;
use mislab::accel::bvh::{Bvh, Presplit};
use mislab::accel::wide_bvh;
use mislab::render::bvh_store::{self, Origin};
use std::path::PathBuf;

/// A fresh folder of its own for each test.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mislab-bvh-store-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// A sphere on a floor: 2,400 triangles, some large (pre-split).
fn tris() -> Vec<[Vec3; 3]> {
    let mut t = uv_sphere(Vec3::new(0.0, 1.0, 0.0), 1.0, 40, 31, true);
    t.extend(rect(Vec3::new(-50.0, 0.0, -50.0), Vec3::new(100.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 100.0)));
    t
}

fn same(a: &Bvh, b: &Bvh) {
    assert_eq!(a.prim_refs, b.prim_refs, "references");
    assert_eq!(a.wide, b.wide, "wide nodes");
    assert_eq!(a.nodes, b.nodes, "the BVH2 root");
    assert_eq!(a.sah_cost, b.sah_cost, "SAH");
}

#[test]
fn a_stored_tree_reads_back_equal_to_the_build() {
    let dir = folder("equal");
    let t = tris();
    let built = wide_bvh::build(&t, &[], &[], Presplit::Large { keep_whole: &[] });
    let (first, o1) = bvh_store::build_in(&dir, &t, &[], &[], Presplit::Large { keep_whole: &[] });
    let (second, o2) = bvh_store::build_in(&dir, &t, &[], &[], Presplit::Large { keep_whole: &[] });
    assert_eq!((o1, o2), (Origin::Built, Origin::Loaded));
    same(&first, &built);
    same(&second, &built);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_damaged_or_foreign_file_is_refused_and_rebuilt() {
    let dir = folder("damaged");
    let t = tris();
    let key = bvh_store::key(&t, &[], &[], &Presplit::Off);
    let (built, _) = bvh_store::build_in(&dir, &t, &[], &[], Presplit::Off);
    let path = bvh_store::file_for(&dir, key);
    let mut bytes = std::fs::read(&path).expect("the stored file");
    let n = bytes.len();
    bytes[n / 2] ^= 0x40;
    std::fs::write(&path, &bytes).expect("damages it");
    let (again, origin) = bvh_store::build_in(&dir, &t, &[], &[], Presplit::Off);
    assert!(matches!(&origin, Origin::Rebuilt(why) if why.contains("checksum")), "{origin:?}");
    same(&again, &built);
    assert_eq!(bvh_store::build_in(&dir, &t, &[], &[], Presplit::Off).1, Origin::Loaded, "rewritten whole");
    // Truncated.
    std::fs::write(&path, &std::fs::read(&path).unwrap()[..n - 3]).unwrap();
    assert!(matches!(bvh_store::build_in(&dir, &t, &[], &[], Presplit::Off).1, Origin::Rebuilt(_)));
    // Another input's file, whole and valid, under this input's name: its key and counts say so.
    let mut moved = t.clone();
    moved[7][1].y += 0.25;
    let other = bvh_store::key(&moved, &[], &[], &Presplit::Off);
    assert_ne!(other, key, "one moved vertex is another input");
    bvh_store::build_in(&dir, &moved, &[], &[], Presplit::Off);
    std::fs::copy(bvh_store::file_for(&dir, other), &path).unwrap();
    let (fresh, origin) = bvh_store::build_in(&dir, &t, &[], &[], Presplit::Off);
    assert!(matches!(&origin, Origin::Rebuilt(why) if why.contains("another scene")), "{origin:?}");
    same(&fresh, &built);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_input_the_build_reads_is_in_the_key() {
    let t = tris();
    let base = bvh_store::key(&t, &[], &[], &Presplit::Off);
    let split = bvh_store::key(&t, &[], &[], &Presplit::Large { keep_whole: &[] });
    let whole = vec![true; t.len()];
    let kept = bvh_store::key(&t, &[], &[], &Presplit::Large { keep_whole: &whole });
    let fewer = bvh_store::key(&t[1..], &[], &[], &Presplit::Off);
    let sphere = mislab::gpu::types::GpuSphere { center: [0.0, 3.0, 0.0], radius: 0.5, ..Default::default() };
    let with_sphere = bvh_store::key(&t, &[sphere], &[], &Presplit::Off);
    let keys = [base, split, kept, fewer, with_sphere];
    for (i, a) in keys.iter().enumerate() {
        for b in &keys[i + 1..] {
            assert_ne!(a, b, "two different inputs share a key: {keys:x?}");
        }
    }
    assert_eq!(base, bvh_store::key(&t.clone(), &[], &[], &Presplit::Off), "the same input, the same key");
}

#[test]
fn the_folder_stays_bounded_oldest_first() {
    let dir = folder("bounded");
    std::fs::create_dir_all(&dir).unwrap();
    let names = ["a.bvh", "b.bvh", "c.bvh"];
    for (i, n) in names.iter().enumerate() {
        std::fs::write(dir.join(n), vec![0u8; 1000]).unwrap();
        let t = std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(1_000_000 + i as u64);
        std::fs::File::options().write(true).open(dir.join(n)).unwrap().set_modified(t).unwrap();
    }
    std::fs::write(dir.join("other.txt"), vec![0u8; 5000]).unwrap();
    // The newest is "c"; "a" is the one just written (kept whatever its time).
    mislab::io::cache_file::evict(&dir, "bvh", 2000, &dir.join("a.bvh"));
    let left: Vec<bool> = names.iter().map(|n| dir.join(n).exists()).collect();
    assert_eq!(left, [true, false, true], "the oldest file other than the one just written goes first");
    assert!(dir.join("other.txt").exists(), "only .bvh files are the store's");
    let _ = std::fs::remove_dir_all(&dir);
}
