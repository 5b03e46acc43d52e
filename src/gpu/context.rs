//! The GPU context: one Vulkan adapter + device, chosen by `WGPU_ADAPTER_NAME` or by preference,
//! with the limits the renderer needs and helpers that never wait on the device without a timeout.

use super::pipeline_request::PipelineRequest;
use super::pipeline_store::{self, PipelineStore};
use std::time::Duration;

/// How long any single wait on the device may take before we give up (lavapipe has no watchdog).
pub const DEVICE_WAIT_TIMEOUT: Duration = Duration::from_secs(120);

/// How long the first dispatch of a new pipeline may take: lavapipe compiles a pipeline at its first use, and
/// Mesa 25.0's compile of the generic (unspecialised) render kernel alone took over 120 s on 2 busy cores.
pub const PIPELINE_COMPILE_TIMEOUT: Duration = Duration::from_secs(900);

/// Why no GPU context could be made. The CLI maps every variant to exit code 2.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No Vulkan adapter at all.
    #[error(
        "no Vulkan adapter found. mislab needs a Vulkan driver; on a machine without a GPU install the software \
         rasterizer lavapipe (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`)"
    )]
    NoAdapter,
    /// `WGPU_ADAPTER_NAME` matched none of the adapters.
    #[error("WGPU_ADAPTER_NAME={wanted:?} matches no Vulkan adapter; available: {available}")]
    NoMatchingAdapter { wanted: String, available: String },
    /// The device could not be created.
    #[error("could not open a device on '{adapter}': {source}")]
    RequestDevice { adapter: String, source: wgpu::RequestDeviceError },
    /// A wait on the device failed or timed out.
    #[error("waiting on the GPU failed: {0}")]
    Poll(String),
    /// A buffer could not be mapped for readback.
    #[error("reading back from the GPU failed: {0}")]
    Map(String),
    /// A scene buffer exceeds the device's storage-buffer binding limit.
    #[error(
        "the scene is too large for this device: its {buffer} need {:.1} MiB ({bytes} bytes), more than the \
         device's max_storage_buffer_binding_size of {} MiB ({limit} bytes)",
        *bytes as f64 / (1u64 << 20) as f64,
        limit >> 20
    )]
    SceneTooLarge { buffer: &'static str, bytes: u64, limit: u64 },
    /// The texels exceed two storage bindings, split at a texture boundary (`gpu_scene::split_texels`).
    #[error(
        "the scene is too large for this device: its texels need {:.1} MiB ({bytes} bytes); split at a texture \
         boundary over two bindings, the second needs {:.1} MiB ({second} bytes), more than the device's \
         max_storage_buffer_binding_size of {} MiB ({limit} bytes)",
        *bytes as f64 / (1u64 << 20) as f64,
        *second as f64 / (1u64 << 20) as f64,
        limit >> 20
    )]
    TexelsTooLarge { bytes: u64, second: u64, limit: u64 },
    /// The triangle vertices exceed all the storage bindings they may take (`gpu_scene::split_vertices`).
    #[error(
        "the scene is too large for this device: its triangle vertices need {:.1} MiB ({bytes} bytes), more than \
         the {bindings} bindings they may take hold at the device's max_storage_buffer_binding_size of {} MiB \
         ({limit} bytes) each, whole triangles per binding",
        *bytes as f64 / (1u64 << 20) as f64,
        limit >> 20
    )]
    VerticesTooLarge { bytes: u64, bindings: usize, limit: u64 },
}

/// One adapter as `mislab info` prints it.
#[derive(Clone, Debug)]
pub struct AdapterSummary {
    /// Adapter name (what `WGPU_ADAPTER_NAME` matches, case-insensitively, as a substring).
    pub name: String,
    /// Discrete / integrated / CPU / ...
    pub device_type: wgpu::DeviceType,
    /// Driver name and version.
    pub driver: String,
}

/// Adapter, device and queue, plus what was learned about them. A clone is another handle to the same device.
#[derive(Clone)]
pub struct GpuContext {
    /// The instance the adapter came from (kept alive for surfaces).
    pub instance: wgpu::Instance,
    /// The chosen adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter information.
    pub info: wgpu::AdapterInfo,
    /// Whether timestamp queries work inside compute passes.
    pub timestamps: bool,
    /// Compute pipelines built on this device, shared by everything that renders on it (`PipelineMemo`).
    pub pipelines: PipelineMemo,
}

/// Compute pipelines built on one device, by a fingerprint their builder computes from everything that makes
/// them differ (source, entry point, constants, layout). lavapipe compiles a render pipeline for seconds, so two
/// renderers of equal pipelines on one device (a bench's configurations, a test binary's renders, the stress
/// suite's cases) build it once. Across processes the driver's own cache, kept on disk, does the same
/// (`PipelineStore`, where the device offers one).
#[derive(Clone, Default)]
pub struct PipelineMemo {
    built: std::sync::Arc<std::sync::Mutex<std::collections::HashMap<u64, wgpu::ComputePipeline>>>,
    store: Option<std::sync::Arc<PipelineStore>>,
    /// Pipelines built ahead of their builder from a forecast (`render::pipeline_forecast`), each with the request
    /// it was built from: taken only for an equal request (`take_offer`).
    offered: std::sync::Arc<std::sync::Mutex<Vec<(PipelineRequest, wgpu::ComputePipeline)>>>,
    /// The request of the last pipeline a builder asked for (`note_request`), for the next run's forecast.
    last: std::sync::Arc<std::sync::Mutex<Option<PipelineRequest>>>,
    /// How many offered pipelines were taken.
    taken: std::sync::Arc<std::sync::atomic::AtomicUsize>,
}

impl PipelineMemo {
    /// The pipeline with `fingerprint`, if one was built on this device.
    pub fn get(&self, fingerprint: u64) -> Option<wgpu::ComputePipeline> {
        self.built.lock().unwrap_or_else(|e| e.into_inner()).get(&fingerprint).cloned()
    }

    /// Remembers `pipeline` under `fingerprint`.
    pub fn insert(&self, fingerprint: u64, pipeline: &wgpu::ComputePipeline) {
        self.built.lock().unwrap_or_else(|e| e.into_inner()).insert(fingerprint, pipeline.clone());
    }

    /// How many pipelines are remembered.
    pub fn len(&self) -> usize {
        self.built.lock().unwrap_or_else(|e| e.into_inner()).len()
    }

    /// Whether none is.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The driver's pipeline cache kept on disk, where the device has one: every pipeline is built through it.
    pub fn store(&self) -> Option<&PipelineStore> {
        self.store.as_deref()
    }

    /// Holds `pipeline`, built from `request` ahead of any builder asking for it.
    pub fn offer(&self, request: PipelineRequest, pipeline: wgpu::ComputePipeline) {
        self.offered.lock().unwrap_or_else(|e| e.into_inner()).push((request, pipeline));
    }

    /// The pipeline offered for a request equal to `request` in every field, if any (it is handed out once).
    pub fn take_offer(&self, request: &PipelineRequest) -> Option<wgpu::ComputePipeline> {
        let mut offered = self.offered.lock().unwrap_or_else(|e| e.into_inner());
        let i = offered.iter().position(|(r, _)| r == request)?;
        self.taken.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Some(offered.swap_remove(i).1)
    }

    /// How many offered pipelines builders have taken (`take_offer`).
    pub fn offers_taken(&self) -> usize {
        self.taken.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Records the request of the pipeline a builder is using now.
    pub fn note_request(&self, request: PipelineRequest) {
        *self.last.lock().unwrap_or_else(|e| e.into_inner()) = Some(request);
    }

    /// The request `note_request` saw last.
    pub fn last_request(&self) -> Option<PipelineRequest> {
        self.last.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

fn summary(a: &wgpu::Adapter) -> AdapterSummary {
    let i = a.get_info();
    AdapterSummary { name: i.name, device_type: i.device_type, driver: format!("{} {}", i.driver, i.driver_info) }
}

/// Mesa's implicit device-selection layer connects to a Wayland display while it lists the devices, and where no
/// desktop session exists (CI, ssh, a container) libwayland then prints "error: XDG_RUNTIME_DIR is invalid or not
/// set in the environment" twice per Vulkan instance — noise a user takes for mislab's error. mislab chooses its
/// adapter itself (`WGPU_ADAPTER_NAME`, else by device type), so without a session the layer is switched off
/// through its documented `NODEVICE_SELECT` variable: once, before this process makes any Vulkan call (every
/// instance, the viewer's too, is made after `quiet_device_select_layer`), and never against the user's choice.
pub fn quiet_device_select_layer() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let session = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
        if !session && std::env::var_os("NODEVICE_SELECT").is_none() {
            std::env::set_var("NODEVICE_SELECT", "1");
        }
    });
}

/// lavapipe (Mesa's software Vulkan) compiles a render kernel to 8-lane code by default on AVX2 CPUs, and on Mesa
/// 25 that takes 2.8–3.3 s for a BVH scene's kernel, most of it in LLVM over code that grows with the lane count
/// (every storage load is unrolled per lane). 4-lane code compiles in 1.6–1.9 s and renders as fast (within ±7 %,
/// the same pixels; docs/performance.md, "Time to an image"). So where the user has not chosen a width, lavapipe is
/// asked for 128-bit vectors through its documented `LP_NATIVE_VECTOR_WIDTH`, once, before this process makes any
/// Vulkan call. Only lavapipe and llvmpipe read the variable: GPU drivers are unaffected.
pub fn lavapipe_vector_width() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if std::env::var_os("LP_NATIVE_VECTOR_WIDTH").is_none() {
            std::env::set_var("LP_NATIVE_VECTOR_WIDTH", LAVAPIPE_VECTOR_BITS);
        }
    });
}

/// The vector width (bits) `lavapipe_vector_width` asks lavapipe for.
pub const LAVAPIPE_VECTOR_BITS: &str = "128";

/// What this process sets in the environment before its first Vulkan call (`quiet_device_select_layer`,
/// `lavapipe_vector_width`); every instance, the viewer's too, is made after it.
pub fn prepare_driver_environment() {
    quiet_device_select_layer();
    lavapipe_vector_width();
}

fn vulkan_instance() -> wgpu::Instance {
    prepare_driver_environment();
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    wgpu::Instance::new(desc)
}

/// Every Vulkan adapter on this machine.
pub fn list_adapters() -> Vec<AdapterSummary> {
    let instance = vulkan_instance();
    pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN)).iter().map(summary).collect()
}

fn preference(t: wgpu::DeviceType) -> u32 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// The adapter `GpuContext::new` opens: the one named by `WGPU_ADAPTER_NAME`, else the most capable.
fn choose_adapter(instance: &wgpu::Instance) -> Result<wgpu::Adapter, GpuError> {
    let mut adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
    if adapters.is_empty() {
        return Err(GpuError::NoAdapter);
    }
    let adapter = match std::env::var("WGPU_ADAPTER_NAME").ok().filter(|s| !s.is_empty()) {
        Some(wanted) => {
            let w = wanted.to_lowercase();
            match adapters.iter().position(|a| a.get_info().name.to_lowercase().contains(&w)) {
                Some(i) => adapters.swap_remove(i),
                None => {
                    let available = adapters.iter().map(|a| a.get_info().name).collect::<Vec<_>>().join(", ");
                    return Err(GpuError::NoMatchingAdapter { wanted, available });
                }
            }
        }
        None => {
            adapters.sort_by_key(|a| preference(a.get_info().device_type));
            adapters.swap_remove(0)
        }
    };
    Ok(adapter)
}

/// The storage-binding limit (bytes) of the adapter `GpuContext::new` would open, without opening a device,
/// or None without one: lets loaders refuse what the device cannot hold before decoding it.
pub fn chosen_adapter_storage_limit() -> Option<u64> {
    let adapter = choose_adapter(&vulkan_instance()).ok()?;
    let l = adapter.limits();
    Some((l.max_storage_buffer_binding_size as u64).min(l.max_buffer_size))
}

impl GpuContext {
    /// Opens a headless device: the adapter named by `WGPU_ADAPTER_NAME` (substring, case-insensitive)
    /// or else the most capable one (discrete > integrated > ... > CPU).
    pub fn new() -> Result<Self, GpuError> {
        let instance = vulkan_instance();
        let adapter = choose_adapter(&instance)?;
        Self::from_adapter(instance, adapter)
    }

    /// Opens a device on a given adapter (the viewer picks one compatible with its surface).
    pub fn from_adapter(instance: wgpu::Instance, adapter: wgpu::Adapter) -> Result<Self, GpuError> {
        let info = adapter.get_info();
        let (features, limits) = Self::wanted(&adapter);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("mislab"),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|source| GpuError::RequestDevice { adapter: info.name.clone(), source })?;
        let timestamps = features.contains(wgpu::Features::TIMESTAMP_QUERY);
        let store = match (features.contains(wgpu::Features::PIPELINE_CACHE), pipeline_store::cache_dir()) {
            (true, Some(dir)) => {
                let (store, note) = PipelineStore::open(&device, &info, &dir);
                if let Some(note) = note {
                    eprintln!("warning: pipeline cache {note}");
                }
                store.map(std::sync::Arc::new)
            }
            _ => None,
        };
        let pipelines = PipelineMemo { store, ..Default::default() };
        Ok(GpuContext { instance, adapter, device, queue, info, timestamps, pipelines })
    }

    /// A context on a device opened elsewhere with `wanted`'s features and limits (a web page's, through eframe,
    /// where nothing may block): no pipeline store.
    pub fn from_device(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Self {
        let info = adapter.get_info();
        let timestamps = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        GpuContext { instance, adapter, device, queue, info, timestamps, pipelines: PipelineMemo::default() }
    }

    /// The features and limits we ask for: everything the adapter offers that we use.
    pub fn wanted(adapter: &wgpu::Adapter) -> (wgpu::Features, wgpu::Limits) {
        let available = adapter.features();
        // SUBGROUP: the traversal's speculative vote (shaders/bvh.wgsl bvh_all_lanes, src/render/shaders.rs for_device).
        // SHADER_INT64: 32-byte loads of vertices and nodes (shaders/geometry_loads_int64.wgsl, same place).
        // PIPELINE_CACHE: compiled pipelines kept across processes (`PipelineStore`).
        let features = available
            & (wgpu::Features::TIMESTAMP_QUERY
                | wgpu::Features::PIPELINE_CACHE
                | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
                | wgpu::Features::SUBGROUP
                | wgpu::Features::SHADER_INT64);
        (features, adapter.limits())
    }

    /// The device's limits.
    pub fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }

    /// Largest storage-buffer binding, in bytes (what a scene buffer must fit in).
    pub fn max_storage_binding(&self) -> u64 {
        let l = self.limits();
        (l.max_storage_buffer_binding_size as u64).min(l.max_buffer_size)
    }

    /// Waits for all submitted work, at most `DEVICE_WAIT_TIMEOUT`.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.wait_at_most(DEVICE_WAIT_TIMEOUT)
    }

    /// Waits for all submitted work, at most `timeout`.
    pub fn wait_at_most(&self, timeout: Duration) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: Some(timeout) })
            .map(|_| ())
            .map_err(|e| GpuError::Poll(e.to_string()))
    }

    /// Copies `size` bytes of `src` (from offset 0) to the CPU. `src` needs COPY_SRC.
    pub fn read_buffer(&self, src: &wgpu::Buffer, size: u64) -> Result<Vec<u8>, GpuError> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(src, 0, &staging, 0, size);
        self.queue.submit([enc.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        match rx.recv_timeout(Duration::from_secs(5)) {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(GpuError::Map(e.to_string())),
            Err(_) => return Err(GpuError::Map("the map callback never ran".into())),
        }
        let data = staging.get_mapped_range(..).map_err(|e| GpuError::Map(format!("{e:?}")))?.to_vec();
        staging.unmap();
        Ok(data)
    }

    /// Reads a buffer of `count` Pod values.
    pub fn read_pod<T: bytemuck::Pod>(&self, src: &wgpu::Buffer, count: usize) -> Result<Vec<T>, GpuError> {
        let bytes = self.read_buffer(src, (count * std::mem::size_of::<T>()) as u64)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// A storage buffer initialised with `data` (at least 16 bytes, so empty tables still bind).
    pub fn storage_buffer<T: bytemuck::Pod>(&self, label: &str, data: &[T], extra: wgpu::BufferUsages) -> wgpu::Buffer {
        self.storage_buffer_padded(label, bytemuck::cast_slice(data), std::mem::size_of::<T>(), extra)
    }

    /// A read-only storage buffer of raw bytes holding elements of `element_size` bytes (an empty one gets one
    /// zero element, as `storage_buffer`).
    pub fn storage_buffer_bytes(&self, label: &str, bytes: &[u8], element_size: usize) -> wgpu::Buffer {
        self.storage_buffer_padded(label, bytes, element_size, wgpu::BufferUsages::empty())
    }

    fn storage_buffer_padded(
        &self,
        label: &str,
        bytes: &[u8],
        element_size: usize,
        extra: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        let min = 16.max(element_size);
        let mut bytes = std::borrow::Cow::Borrowed(bytes);
        if bytes.len() < min {
            bytes.to_mut().resize(min, 0);
        }
        self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | extra,
        })
    }
}

/// The adapter summaries plus the limits that matter, as `mislab info` prints them.
pub fn describe(ctx: &GpuContext) -> String {
    let l = ctx.limits();
    let mut s = String::new();
    s += &format!(
        "adapter: {} ({:?}, driver {} {})\n",
        ctx.info.name, ctx.info.device_type, ctx.info.driver, ctx.info.driver_info
    );
    s += &format!("  max storage buffer binding: {} MiB\n", l.max_storage_buffer_binding_size as u64 >> 20);
    s += &format!("  max buffer size: {} MiB\n", l.max_buffer_size >> 20);
    s += &format!("  max storage buffers per stage: {}\n", l.max_storage_buffers_per_shader_stage);
    s += &format!("  max workgroups per dimension: {}\n", l.max_compute_workgroups_per_dimension);
    s += &format!("  max invocations per workgroup: {}\n", l.max_compute_invocations_per_workgroup);
    s += &format!("  max workgroup storage: {} KiB\n", l.max_compute_workgroup_storage_size >> 10);
    s += &format!("  timestamp queries: {}\n", if ctx.timestamps { "yes" } else { "no" });
    let subgroups = ctx.device.features().contains(wgpu::Features::SUBGROUP);
    s += &format!(
        "  subgroup operations: {}\n",
        if subgroups {
            format!(
                "yes, {}-{} lanes (speculative BVH traversal)",
                ctx.info.subgroup_min_size, ctx.info.subgroup_max_size
            )
        } else {
            "no (plain while-while BVH traversal)".to_string()
        }
    );
    s
}
