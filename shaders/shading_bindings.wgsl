// shading_bindings.wgsl — materials, lights, textures and environment (group 0, bindings 5–12) and the
// per-render state (group 1: frame parameters, accumulation, counters, sampler tables).

@group(0) @binding(5) var<storage, read> tri_shading: array<TriShading>;
@group(0) @binding(6) var<storage, read> materials: array<Material>;
@group(0) @binding(7) var<storage, read> lights: array<Light>;
@group(0) @binding(8) var<storage, read> light_alias: array<AliasEntry>;
@group(0) @binding(9) var<storage, read> tex_info: array<TextureInfo>;
@group(0) @binding(10) var<storage, read> tex_texels: array<u32>;
// Environment texels: rgb radiance (unscaled) and, in w, the texel's sampling density in (u, v).
@group(0) @binding(11) var<storage, read> env_texels: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read> env_alias: array<AliasEntry>;

@group(1) @binding(0) var<uniform> params: FrameParams;
@group(1) @binding(1) var<storage, read_write> accum: array<Accum>;
// counters[0]: non-finite samples; counters[1]: rays traced (both read and cleared by the host after
// each submission, which sums them in 64 bits).
@group(1) @binding(2) var<storage, read_write> counters: array<atomic<u32>>;
// The samplers' constant tables (src/samplers.rs `sampler_data`: Sobol matrices, primes, blue-noise mask).
@group(1) @binding(3) var<storage, read> sampler_data: array<u32>;

/// Rays traced by this invocation (summed into counters[1] once per invocation).
var<private> rays_traced: u32;
