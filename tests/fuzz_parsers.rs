//! A short, deterministic mutation fuzz of the importers (pbrt-v4 and Mitsuba 3 XML scenes, PLY, OBJ, TGA and PFM
//! readers), seeded with the bad-import corpus and the Bitterli / Mitsuba scene files: every mutant must load or
//! give an error that names a file in one short line each — never a panic. `fuzz/fuzz_targets/importers.rs` is the
//! open-ended `cargo fuzz` twin of this loop; the fixed seed and count keep CI's run to a few seconds.
//!
//! The Bitterli scenes reference 20 MB of meshes and textures each; their mutants load stand-ins (one small PLY,
//! TGA and PFM under the same directory names) so that a mutant that stays valid is parsed to the end, fast.

use std::path::PathBuf;

fn shared(rel: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/")).join(rel)
}

fn corpus(rel: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/bad-import/")).join(rel)
}

/// xorshift64*: the same mutants on every run and machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Tokens a parser should meet at every place: wrong types, limits, delimiters, NaN, self-inclusion.
const TOKENS: &[&str] = &[
    "-1",
    "0",
    "4294967296",
    "18446744073709551617",
    "1e39",
    "-1e39",
    "nan",
    "inf",
    "1e-45",
    "\"",
    "[ ",
    " ]",
    "\n",
    "<",
    "/>",
    "&amp;",
    "$x",
    "\"float\"",
    "\"integer indices\" [ 0 1 99999 ]",
    "Include \"case.pbrt\"",
    "<include filename=\"case.xml\"/>",
    "AttributeEnd",
    "ObjectInstance \"nothing\"",
    "element vertex 4000000000\n",
    "property list uchar int vertex_indices\n",
];

const BYTES: &[u8] = &[0, 0xff, b'"', b'[', b']', b'<', b'>', b'/', b'#', b'\n', b' ', b'-', b'9', 0x80, b'.'];

/// One to four random edits of `seed`: bit flips, odd bytes, deletions, duplications, odd tokens, truncation.
fn mutate(rng: &mut Rng, seed: &[u8]) -> Vec<u8> {
    let mut v = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(v.len() + 1);
        match rng.below(7) {
            0 if !v.is_empty() => {
                let i = at.min(v.len() - 1);
                v[i] ^= 1 << rng.below(8);
            }
            1 if !v.is_empty() => {
                let i = at.min(v.len() - 1);
                v[i] = BYTES[rng.below(BYTES.len())];
            }
            2 => {
                let end = (at + 1 + rng.below(16)).min(v.len());
                v.drain(at.min(end)..end);
            }
            3 => {
                let end = (at + 1 + rng.below(64)).min(v.len());
                let part: Vec<u8> = v[at.min(end)..end].to_vec();
                let to = rng.below(v.len() + 1);
                v.splice(to..to, part);
            }
            4 | 5 => {
                // Prefer a token boundary: the byte after the next space or newline.
                let mut i = at;
                while i < v.len() && !matches!(v[i], b' ' | b'\n') {
                    i += 1;
                }
                let i = (i + 1).min(v.len());
                let t = TOKENS[rng.below(TOKENS.len())].as_bytes();
                if rng.below(2) == 0 {
                    // Replace the word there.
                    let mut j = i;
                    while j < v.len() && !matches!(v[j], b' ' | b'\n') {
                        j += 1;
                    }
                    v.splice(i..j, t.iter().copied());
                } else {
                    v.splice(i..i, t.iter().copied());
                }
            }
            _ => v.truncate(at),
        }
    }
    v
}

/// Runs `f` and turns a panic into an error message (printing nothing).
fn no_panic<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).map_err(|p| {
        p.downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default()
    })
}

/// A small binary PLY (one of the living room's meshes), a TGA and a PFM: the stand-ins and decoder seeds.
fn small_files() -> (Vec<u8>, Vec<u8>, Vec<u8>) {
    let ply = std::fs::read(shared("testdata/scenes/bitterli/living-room/pbrt-v4/models/Mesh008.ply")).unwrap();
    // Uncompressed 24-bit TGA, 4×2, bottom-up.
    let mut tga = vec![0u8, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 4, 0, 2, 0, 24, 0];
    tga.extend((0..4 * 2 * 3).map(|i| (i * 37 % 256) as u8));
    // Colour PFM, 3×2, little-endian.
    let mut pfm = b"PF\n3 2\n-1.0\n".to_vec();
    pfm.extend((0..3 * 2 * 3).flat_map(|i| (i as f32 * 0.25).to_le_bytes()));
    (ply, tga, pfm)
}

/// The scene text with every mesh and texture reference pointing at a stand-in.
fn with_stand_ins(text: &str) -> String {
    let mut out = String::new();
    for (k, part) in text.split('"').enumerate() {
        if k > 0 {
            out.push('"');
        }
        let lower = part.to_ascii_lowercase();
        let dir = part.rsplit_once('/').map(|(d, _)| d);
        out += match (dir, lower.rsplit_once('.').map(|(_, e)| e)) {
            (Some("models"), Some("ply")) => "models/small.ply",
            (Some("textures"), Some("tga")) => "textures/small.tga",
            (Some("textures"), Some("pfm")) => "textures/small.pfm",
            _ => part,
        };
    }
    out
}

struct Failures {
    list: Vec<String>,
    cases: usize,
}

impl Failures {
    fn check(&mut self, what: &str, result: Result<Result<(), String>, String>, names: &[String]) {
        self.cases += 1;
        match result {
            Err(panic) => self.list.push(format!("{what}: panicked: {panic}")),
            Ok(Err(msg)) => {
                if msg.trim().is_empty() {
                    self.list.push(format!("{what}: an empty error"));
                } else if let Some(l) = msg.lines().find(|l| l.chars().count() >= 1000) {
                    self.list.push(format!("{what}: an error line of {} characters", l.chars().count()));
                } else if !names.is_empty() && !names.iter().any(|n| msg.contains(n.as_str())) {
                    self.list.push(format!("{what}: the error names no file: {msg}"));
                }
            }
            Ok(Ok(())) => {}
        }
    }
}

#[test]
fn mutated_scenes_and_files_are_errors_never_panics() {
    let start = std::time::Instant::now();
    let dir = std::env::temp_dir().join(format!("mislab-fuzz-parsers-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for sub in ["models", "textures"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    let (ply, tga, pfm) = small_files();
    std::fs::write(dir.join("models/small.ply"), &ply).unwrap();
    std::fs::write(dir.join("textures/small.tga"), &tga).unwrap();
    std::fs::write(dir.join("textures/small.pfm"), &pfm).unwrap();
    // The bad-import corpus beside the mutants: its files include and reference each other by name.
    let mut seeds: Vec<(String, Vec<u8>)> = vec![];
    for e in std::fs::read_dir(corpus("")).expect("tests/data/bad-import") {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        std::fs::copy(&p, dir.join(&name)).unwrap();
        seeds.push((name, std::fs::read(&p).unwrap()));
    }
    let bitterli = shared("testdata/scenes/bitterli");
    for scene in
        ["cornell-box", "veach-mis", "living-room", "dining-room", "staircase2", "veach-ajar", "material-testball"]
    {
        let p = bitterli.join(scene).join("pbrt-v4/scene-v4.pbrt");
        let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        seeds.push((format!("{scene}.pbrt"), with_stand_ins(&text).into_bytes()));
    }
    for (scene, file) in [("cornell-box", "scene_v3.xml"), ("veach-mis", "scene.xml")] {
        let p = bitterli.join(scene).join("mitsuba3").join(file);
        seeds.push((format!("{scene}.xml"), std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))));
    }
    let obj = b"# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/1/1\nf -1 -2 -3\n";
    seeds.push(("seed.obj".into(), obj.to_vec()));
    seeds.push(("seed.ply".into(), ply));
    seeds.push(("seed.tga".into(), tga));
    seeds.push(("seed.pfm".into(), pfm));
    seeds.sort();
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .chain(["case.pbrt".into(), "case.xml".into()])
        .collect();

    std::panic::set_hook(Box::new(|_| {}));
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut f = Failures { list: vec![], cases: 0 };
    // Scene loads cost milliseconds (the env maps' resampling most); the decoders microseconds.
    const SCENE_MUTANTS: usize = 32;
    const FILE_MUTANTS: usize = 600;
    let mut seen = std::collections::HashMap::<&str, usize>::new();
    for (name, seed) in &seeds {
        let ext = name.rsplit_once('.').map(|(_, e)| e).unwrap_or_default();
        *seen
            .entry(match ext {
                "pbrt" => "pbrt",
                "xml" => "xml",
                "ply" => "ply",
                "obj" => "obj",
                "tga" => "tga",
                "pfm" => "pfm",
                _ => "other",
            })
            .or_default() += 1;
        let count = if matches!(ext, "pbrt" | "xml") { SCENE_MUTANTS } else { FILE_MUTANTS };
        for k in 0..count {
            let m = mutate(&mut rng, seed);
            let what = format!("{name} mutant {k}");
            match ext {
                "pbrt" | "xml" => {
                    let path = dir.join(format!("case.{ext}"));
                    std::fs::write(&path, &m).unwrap();
                    let r = no_panic(|| {
                        let r = if ext == "pbrt" {
                            mislab::scene::pbrt::load(&path)
                        } else {
                            mislab::scene::mitsuba::load(&path)
                        };
                        r.map(|_| ()).map_err(|e| e.to_string())
                    });
                    f.check(&what, r, &names);
                }
                "ply" => f.check(&what, no_panic(|| mislab::scene::ply::decode(&m).map(|_| ())), &[]),
                "obj" => {
                    let text = String::from_utf8_lossy(&m);
                    f.check(&what, no_panic(|| mislab::scene::obj::decode(&text).map(|_| ())), &[])
                }
                "tga" => f.check(&what, no_panic(|| mislab::scene::tga::decode(&m).map(|_| ())), &[]),
                "pfm" => f.check(&what, no_panic(|| mislab::scene::pfm::decode(&m).map(|_| ())), &[]),
                _ => {}
            }
        }
    }
    let _ = std::panic::take_hook();
    let _ = std::fs::remove_dir_all(&dir);
    eprintln!("{} mutants of {} seeds ({seen:?}) in {:.1} s", f.cases, seeds.len(), start.elapsed().as_secs_f64());
    for kind in ["pbrt", "xml", "ply", "obj", "tga", "pfm"] {
        assert!(seen.get(kind).copied().unwrap_or(0) > 0, "no {kind} seed: the corpus moved?");
    }
    assert!(f.list.is_empty(), "{} of {} mutants failed:\n{}", f.list.len(), f.cases, f.list.join("\n"));
}
