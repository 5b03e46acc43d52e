//! Render state files: the device's raw accumulators (per-pixel Welford mean, second moment, count and NaN/Inf
//! count, exactly the f32/u32 values the GPU holds) plus a header naming the scene's content hash, the settings,
//! the seed and the range of sample indices the file contains. Restoring them into a renderer and rendering on
//! gives the same bits as a render that was never stopped (samples merge one at a time on the device).
//!
//! Format (all little-endian), documented in docs/cluster.md:
//! `b"MISLABST"`, u32 version, u32 header length, header JSON (UTF-8), width × height records of
//! `{mean: [f32; 3], count: u32, m2: [f32; 3], nonfinite: u32}` (the WGSL `Accum`), then the FNV-1a 64 hash of
//! every byte before it (a truncated or corrupted file is refused instead of resumed).

pub mod error;
pub mod merge;
pub mod session;

pub use error::StateError;

use crate::gpu::types::GpuAccum;
use crate::render::film::Film;
use crate::render::scene_data::SceneData;
use crate::render::settings::Settings;
use crate::scene::Camera;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// First bytes of every state file.
pub const MAGIC: &[u8; 8] = b"MISLABST";
/// Version of the layout above.
pub const VERSION: u32 = 1;
/// Largest header accepted (a corrupted length must not allocate gigabytes).
const MAX_HEADER: usize = 1 << 20;

/// What a state file says about itself.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StateHeader {
    /// The scene as named on the command line (for messages; `scene_hash` is what is compared).
    pub scene: String,
    /// FNV-1a 64 of everything uploaded for the scene and its camera (`scene_hash`), hex.
    pub scene_hash: String,
    /// Every setting of the render (film size and seed included).
    pub settings: Settings,
    /// The seed (also in `settings`; here for people reading the header).
    pub seed: u32,
    /// Samples per pixel of the whole render this file belongs to.
    pub spp_total: u32,
    /// Fixed-count samplers' target (`Renderer::set_sampler_spp`).
    pub sampler_spp: u32,
    /// `--part K/N` (K from 0), or None for a whole render.
    pub part: Option<(u32, u32)>,
    /// Sample indices this file is meant to hold: `[start, end)`.
    pub range: (u32, u32),
    /// Next sample index: the file holds the indices `[range.0, next)`.
    pub next: u32,
    /// NaN/Inf samples counted on the device over `[range.0, next)`.
    pub nonfinite_total: u64,
    /// Rays traced.
    pub rays_total: u64,
    /// Render seconds spent on these samples (all runs together).
    pub seconds: f64,
    /// Software version that wrote it.
    pub mislab_version: String,
}

impl StateHeader {
    /// Samples per pixel the file holds.
    pub fn done(&self) -> u32 {
        self.next - self.range.0
    }

    /// Whether the file holds its whole range.
    pub fn is_complete(&self) -> bool {
        self.next == self.range.1
    }

    /// Why a state cannot continue (or be merged with) a render of `other`: each field that differs, or None.
    pub fn differences(&self, other: &StateHeader) -> Option<String> {
        let mut out = Vec::new();
        if self.scene_hash != other.scene_hash {
            out.push(format!(
                "scene content hash {} (scene '{}') vs {} (scene '{}')",
                self.scene_hash, self.scene, other.scene_hash, other.scene
            ));
        }
        let (a, b) = (settings_map(&self.settings), settings_map(&other.settings));
        for (k, va) in &a {
            let vb = b.get(k).cloned().unwrap_or(serde_json::Value::Null);
            if *va != vb {
                out.push(format!("{k}: {va} vs {vb}"));
            }
        }
        if self.spp_total != other.spp_total {
            out.push(format!("--spp: {} vs {}", self.spp_total, other.spp_total));
        }
        if self.sampler_spp != other.sampler_spp {
            out.push(format!("sampler target count: {} vs {}", self.sampler_spp, other.sampler_spp));
        }
        (!out.is_empty()).then(|| out.join("; "))
    }
}

/// Settings as a JSON map without `exposure` (display only: it changes no sample).
fn settings_map(s: &Settings) -> serde_json::Map<String, serde_json::Value> {
    let mut m = match serde_json::to_value(s) {
        Ok(serde_json::Value::Object(m)) => m,
        _ => Default::default(),
    };
    m.remove("exposure");
    m
}

/// A state file in memory.
#[derive(Clone, Debug)]
pub struct RenderState {
    /// The header.
    pub header: StateHeader,
    /// The raw accumulators, row-major from the top.
    pub accum: Vec<GpuAccum>,
}

/// FNV-1a 64 (our own: a content fingerprint, not a security hash).
#[derive(Clone, Copy)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Mixes in `bytes`.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    /// Mixes in a length-prefixed slice of plain data (so that moving bytes between fields changes the hash).
    pub fn write_pod<T: bytemuck::Pod>(&mut self, data: &[T]) {
        self.write(&(data.len() as u64).to_le_bytes());
        self.write(bytemuck::cast_slice(data));
    }

    /// The hash.
    pub fn finish(self) -> u64 {
        self.0
    }
}

/// The scene's content hash: every buffer the device gets, the environment parameters and the camera.
pub fn scene_hash(data: &SceneData, camera: &Camera) -> String {
    let mut h = Fnv::default();
    h.write_pod(&data.tri_verts);
    h.write_pod(&data.tri_shading);
    h.write_pod(&data.shading_verts);
    h.write_pod(&data.spheres);
    h.write_pod(&data.quads);
    h.write_pod(&data.materials);
    h.write_pod(&data.lights);
    h.write_pod(&data.light_alias);
    h.write_pod(&data.tex_info);
    h.write_pod(&data.tex_texels);
    h.write_pod(&data.env_texels);
    h.write_pod(&data.env_alias);
    h.write_pod(&[data.env_size.0, data.env_size.1, data.env_light.unwrap_or(u32::MAX)]);
    h.write_pod(&data.env_constant);
    h.write_pod(&[data.env_scale, data.env_rotation, data.offset_scale]);
    h.write_pod(&data.origin.to_array());
    h.write_pod(&data.bvh_nodes);
    h.write_pod(&data.prim_refs);
    h.write_pod(&data.wide_nodes);
    for v in [camera.position, camera.forward, camera.up] {
        h.write_pod(&v.to_array());
    }
    h.write_pod(&[camera.vfov]);
    // A film crop is a different image; the whole film hashes as it did before crops existed.
    if camera.window != Camera::FULL_WINDOW {
        h.write_pod(&camera.window);
    }
    format!("{:016x}", h.finish())
}

impl RenderState {
    /// The state of `film` (the renderer's readback: its values are the device's raw accumulators).
    pub fn from_film(header: StateHeader, film: &Film) -> RenderState {
        let accum = (0..film.mean.len())
            .map(|i| GpuAccum {
                mean: film.mean[i],
                count: film.count[i],
                m2: film.m2[i],
                nonfinite: film.nonfinite[i],
            })
            .collect();
        RenderState { header, accum }
    }

    /// The film these accumulators make.
    pub fn film(&self) -> Film {
        let s = &self.header.settings;
        Film::from_accum(s.width, s.height, &self.accum, self.header.nonfinite_total)
    }

    /// The mean image with a reference EXR's attributes (`mislab bench --ref` reads states through this).
    pub fn reference_image(&self) -> crate::io::exr_image::ReferenceImage {
        let s = &self.header.settings;
        let attributes = merge::exr_attributes(&self.header, 0)
            .into_iter()
            .chain([("stateSamples".to_string(), format!("{}..{}", self.header.range.0, self.header.next))])
            .collect();
        crate::io::exr_image::ReferenceImage {
            width: s.width,
            height: s.height,
            pixels: self.accum.iter().map(|a| a.mean).collect(),
            attributes,
        }
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let json = serde_json::to_vec_pretty(&self.header).expect("a header always serialises");
        let mut out = Vec::with_capacity(24 + json.len() + self.accum.len() * 32);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(&json);
        for a in &self.accum {
            for v in a.mean {
                out.extend_from_slice(&v.to_le_bytes());
            }
            out.extend_from_slice(&a.count.to_le_bytes());
            for v in a.m2 {
                out.extend_from_slice(&v.to_le_bytes());
            }
            out.extend_from_slice(&a.nonfinite.to_le_bytes());
        }
        let mut h = Fnv::default();
        h.write(&out);
        out.extend_from_slice(&h.finish().to_le_bytes());
        out
    }

    /// Parses a state file's bytes; `name` is the file for messages.
    pub fn from_bytes(bytes: &[u8], name: &str) -> Result<RenderState, StateError> {
        let bad = |problem: String| StateError::Invalid { file: name.to_string(), problem };
        if bytes.len() < 16 || &bytes[..8] != MAGIC {
            return Err(bad("it does not start with the mislab state signature 'MISLABST'".into()));
        }
        let version = u32::from_le_bytes(bytes[8..12].try_into().unwrap());
        if version != VERSION {
            return Err(bad(format!("format version {version}; this mislab reads version {VERSION}")));
        }
        let header_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        if header_len > MAX_HEADER || 16 + header_len + 8 > bytes.len() {
            return Err(bad(format!(
                "truncated or corrupted: a {header_len}-byte header does not fit in its {} bytes",
                bytes.len()
            )));
        }
        let body = bytes.len() - 8;
        let mut h = Fnv::default();
        h.write(&bytes[..body]);
        let stored = u64::from_le_bytes(bytes[body..].try_into().unwrap());
        let header: Result<StateHeader, _> = serde_json::from_slice(&bytes[16..16 + header_len]);
        let header = match header {
            Ok(header) => header,
            Err(e) if h.finish() == stored => return Err(bad(format!("its header does not parse: {e}"))),
            Err(_) => return Err(bad("truncated or corrupted (its checksum does not match)".into())),
        };
        let (w, hgt) = (header.settings.width as usize, header.settings.height as usize);
        let expected = 16 + header_len + w * hgt * 32 + 8;
        if bytes.len() != expected {
            return Err(bad(format!(
                "truncated or corrupted: a {w}x{hgt} state is {expected} bytes, the file has {}",
                bytes.len()
            )));
        }
        if h.finish() != stored {
            return Err(bad("corrupted: its checksum does not match its contents".into()));
        }
        let (s, e) = header.range;
        if !(s <= header.next && header.next <= e && e <= header.spp_total) {
            return Err(bad(format!(
                "inconsistent header: sample range {s}..{e}, next {}, total {}",
                header.next, header.spp_total
            )));
        }
        let f32_at = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
        let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
        let accum = (0..w * hgt)
            .map(|i| {
                let o = 16 + header_len + i * 32;
                GpuAccum {
                    mean: [f32_at(o), f32_at(o + 4), f32_at(o + 8)],
                    count: u32_at(o + 12),
                    m2: [f32_at(o + 16), f32_at(o + 20), f32_at(o + 24)],
                    nonfinite: u32_at(o + 28),
                }
            })
            .collect();
        Ok(RenderState { header, accum })
    }

    /// Reads a state file.
    pub fn read(path: &Path) -> Result<RenderState, StateError> {
        let read = |source| StateError::Read { path: path.into(), source };
        // A regular file only: a FIFO or a device in its place must not block or never end.
        let (mut file, _) = crate::io::input_file::open_regular(path).map_err(read)?;
        let mut bytes = Vec::new();
        std::io::Read::read_to_end(&mut file, &mut bytes)
            .map_err(|e| read(crate::io::input_file::InputError::Read(e)))?;
        RenderState::from_bytes(&bytes, &path.display().to_string())
    }

    /// Writes the state atomically (temporary file, fsync, rename).
    pub fn write(&self, path: &Path) -> Result<(), StateError> {
        let bytes = self.to_bytes();
        crate::io::output_file::replace_atomically(path, |tmp| std::fs::write(tmp, &bytes))
            .map_err(|message| StateError::Write { path: path.into(), message })
    }
}
