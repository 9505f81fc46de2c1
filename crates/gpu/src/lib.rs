//! The separable subsurface-scattering pass (Jimenez et al. 2015, *Separable Subsurface
//! Scattering*, Computer Graphics Forum 34(6)) run on a GPU: the WGSL compute shader that
//! `sss-separable` exports ([`sss_separable::shader::wgsl_pass`], i.e.
//! `crates/separable/examples/separable_sss.wgsl` with a kernel pasted in) executed through
//! [`wgpu`] as two compute passes per kernel term, on the same inputs as the CPU filter
//! ([`sss_separable::screen_space`]): irradiance, depth, footprint (mm per pixel) and object
//! ids.
//!
//! Use it to run the filter on a GPU from Rust (`sss filter --gpu`), to measure the pass on an
//! adapter (`cargo bench -p sss-bench --bench gpu`, which prints the adapter's name next to
//! its time), and as the proof that a pasted export gives the CPU filter's picture: the tests
//! compare every pixel with [`sss_separable::screen_space::filter`] with `jitter_radius` 0.
//! An engine that has its own GPU plumbing needs only the shader text.
//!
//! How the passes map to the CPU filter: for each term k of the kernel, the horizontal entry
//! point (`sss_horizontal`) reads the irradiance and writes an intermediate image, and the
//! vertical one (`sss_vertical`) reads that image and writes the output, adding the previous
//! terms' sum (two output textures used in turn), exactly the CPU's `image` and `out` buffers.
//! A rank-1 kernel is exported as one array a with Σ a = R per channel ([`ShaderTaps::Rank1`])
//! and applied in both passes; the vertical pass multiplies by 1 / R, so the 2D kernel is
//! a(x) a(y) / R = h(x) v(y). Textures: irradiance, intermediate and output `rgba32float`,
//! depth and footprint `r32float`, object ids `r32uint` ([`NO_OBJECT`] for none); each pixel
//! is one invocation of an 8 × 8 workgroup. The shader reads texels with `textureLoad` and
//! blends them itself, so its fractions are f32 like the CPU's (no sampler fixed point).
//!
//! What differs from the CPU filter is rounding only: the order of the sums over taps (the
//! shader puts the centre tap first), fused or unfused multiply-adds, the GPU's division
//! (WGSL allows 2.5 ulp) in 1 / mm_per_pixel, which moves tap positions by an ulp or so, and
//! the rank-1 kernel applied as a · a / R instead of h · v. A pixel whose footprint lies within
//! an ulp of the sub-pixel threshold may therefore skip on one side and blur on the other
//! (the tests keep footprints away from it). The tests hold every pixel and channel within
//! 10⁻⁵ relative of the CPU, with a floor of 10⁻⁶ of the channel's largest value for pixels
//! near zero (the bound the CPU filter's own two evaluations are held to); on lavapipe the
//! largest error was under a tenth of that. The GPU pass has no jitter: [`GpuFilter::new`]
//! refuses `jitter_radius` > 0.
//!
//! Adapters: [`Gpu::new`] asks wgpu for its default adapter with the backends that the
//! environment allows (`WGPU_BACKEND=vulkan|gl|...`, `WGPU_ADAPTER_NAME`). Without a GPU,
//! Mesa's software drivers serve: lavapipe (Vulkan, Debian package `mesa-vulkan-drivers`
//! with `libvulkan1`) or llvmpipe through EGL (wgpu's GL backend). No adapter is an error
//! ([`GpuError::NoAdapter`]), never a panic.
//!
//! ```no_run
//! use sss_gpu::{Gpu, GpuFilter};
//! use sss_separable::screen_space::FilterOptions;
//! use sss_separable::{Kernel1d, ScreenInput, SeparableKernel, Tap};
//!
//! let taps = Kernel1d {
//!     taps: vec![
//!         Tap { offset_mm: -1.0, weight: [0.25; 3] },
//!         Tap { offset_mm: 0.0, weight: [0.5; 3] },
//!         Tap { offset_mm: 1.0, weight: [0.25; 3] },
//!     ],
//! };
//! let kernel = SeparableKernel::symmetric(&taps, [0.8, 0.6, 0.4], 1.0)?;
//! let (w, h) = (64, 48);
//! let irradiance = vec![[1.0f32; 3]; w * h];
//! let (depth, mask, mm) = (vec![500.0f32; w * h], vec![0u32; w * h], vec![0.25f32; w * h]);
//! let input = ScreenInput {
//!     width: w,
//!     height: h,
//!     irradiance: &irradiance,
//!     depth: &depth,
//!     mask: &mask,
//!     mm_per_pixel: &mm,
//! };
//! let opts = FilterOptions { jitter_radius: 0.0, ..FilterOptions::default() };
//! let gpu = Gpu::new()?;
//! println!("adapter: {}", gpu.adapter_name());
//! let filter = GpuFilter::new(&gpu, &kernel, &opts)?;
//! let exitance: Vec<[f32; 3]> = filter.filter(&input)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]

#[cfg(doc)]
use sss_separable::NO_OBJECT;
use sss_separable::screen_space::FilterOptions;
use sss_separable::shader::{self, ShaderTaps};
use sss_separable::{Energy, ScreenInput, SeparableKernel};
use std::fmt;

pub use wgpu;

/// Why the GPU pass could not run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GpuError {
    /// No adapter (GPU or software driver) was found, or it gave no device.
    NoAdapter(String),
    /// The inputs, the kernel or the options cannot be run (the message says why).
    Input(String),
    /// wgpu reported an error while creating resources or running the passes.
    Device(String),
}

impl fmt::Display for GpuError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GpuError::NoAdapter(m) => write!(f, "no GPU adapter: {m}"),
            GpuError::Input(m) => write!(f, "{m}"),
            GpuError::Device(m) => write!(f, "GPU error: {m}"),
        }
    }
}

impl std::error::Error for GpuError {}

/// Flattens wgpu's multi-line error text into one line.
fn one_line(text: impl fmt::Display) -> String {
    text.to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// A wgpu device and queue on the adapter wgpu picks (see the crate documentation).
#[derive(Debug)]
pub struct Gpu {
    info: wgpu::AdapterInfo,
    device: wgpu::Device,
    queue: wgpu::Queue,
    max_texture_2d: u32,
}

impl Gpu {
    /// Opens the default adapter (wgpu's environment variables are honoured: `WGPU_BACKEND`,
    /// `WGPU_ADAPTER_NAME`, `WGPU_POWER_PREF`, ...) and a device
    /// on it with the adapter's own limits. Errors with [`GpuError::NoAdapter`] when there is
    /// none.
    pub fn new() -> Result<Gpu, GpuError> {
        let desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(wgpu::util::initialize_adapter_from_env_or_default(
            &instance, None,
        ))
        .map_err(|e| {
            GpuError::NoAdapter(format!(
                "{} (install a driver; without a GPU, Mesa's lavapipe: apt-get install \
                 mesa-vulkan-drivers libvulkan1)",
                one_line(e)
            ))
        })?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("sss-gpu"),
            required_features: wgpu::Features::empty(),
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| {
            GpuError::NoAdapter(format!(
                "{} ({:?}) gave no device: {}",
                info.name,
                info.backend,
                one_line(e)
            ))
        })?;
        Ok(Gpu {
            info,
            device,
            queue,
            max_texture_2d: limits.max_texture_dimension_2d,
        })
    }

    /// What wgpu reports about the adapter.
    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// The adapter's name with its backend and type, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)
    /// (Vulkan, Cpu)`.
    pub fn adapter_name(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }

    /// The device.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }
}

/// Runs `f` inside validation and out-of-memory error scopes of `device` (so that wgpu
/// reports its errors here instead of panicking); the first error caught is returned as
/// [`GpuError::Device`] with `what` in front.
fn checked<T>(device: &wgpu::Device, what: &str, f: impl FnOnce() -> T) -> Result<T, GpuError> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let value = f();
    let errors = [validation.pop(), oom.pop()].map(pollster::block_on);
    match errors.into_iter().flatten().next() {
        Some(e) => Err(GpuError::Device(format!("{what}: {}", one_line(e)))),
        None => Ok(value),
    }
}

/// Blocks until the work submitted to `device` is done.
fn wait(device: &wgpu::Device) -> Result<(), GpuError> {
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map(|_| ())
        .map_err(|e| GpuError::Device(format!("waiting for the GPU: {}", one_line(e))))
}

/// The uniform block `Params` of the shader (32 bytes).
#[derive(Clone, Copy, Debug)]
struct Params {
    support_mm: f32,
    depth_threshold: f32,
    min_footprint_px: f32,
    accumulate: u32,
    out_scale: [f32; 4],
}

impl Params {
    fn bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(32);
        for v in [self.support_mm, self.depth_threshold, self.min_footprint_px] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&self.accumulate.to_le_bytes());
        for v in self.out_scale {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b
    }
}

/// One term's pipelines and the parameters of its two passes.
#[derive(Debug)]
struct Term {
    horizontal: wgpu::ComputePipeline,
    vertical: wgpu::ComputePipeline,
    params: [wgpu::Buffer; 2],
}

/// The exported kernel compiled for one [`Gpu`]: one shader module per term (the example pass
/// with the term's taps pasted in, [`shader::wgsl_pass`]) and its two compute pipelines.
/// Reusable across frames of any size.
#[derive(Debug)]
pub struct GpuFilter {
    device: wgpu::Device,
    queue: wgpu::Queue,
    max_texture_2d: u32,
    layout: wgpu::BindGroupLayout,
    terms: Vec<Term>,
    sources: Vec<String>,
    /// Tells this filter's frames from other filters' ([`GpuFrame::owner`]).
    id: u64,
}

/// Source of [`GpuFilter`] ids.
static NEXT_FILTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Bytes per texel of the rgba32float images.
const RGBA32F: u32 = 16;

fn float_texture(sample_type: wgpu::TextureSampleType, binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

impl GpuFilter {
    /// Compiles `kernel` (as [`ShaderTaps::new`] exports it, weights summing to the kernel's
    /// total weight) for `gpu` with the silhouette and footprint options of `opts`. Errors if
    /// the kernel is empty or not finite, if `opts.jitter_radius` is not 0 (the GPU pass has
    /// no jitter), or if an option is out of range.
    pub fn new(
        gpu: &Gpu,
        kernel: &SeparableKernel,
        opts: &FilterOptions,
    ) -> Result<GpuFilter, GpuError> {
        let input = |m: String| GpuError::Input(m);
        if kernel.terms.is_empty() || !kernel.is_finite() {
            return Err(input(
                "the kernel has no terms or non-finite taps".to_string(),
            ));
        }
        if opts.jitter_radius != 0.0 {
            return Err(input(format!(
                "the GPU pass has no jitter (jitter radius {} given; use 0)",
                opts.jitter_radius
            )));
        }
        if !(opts.depth_threshold > 0.0 && opts.depth_threshold.is_finite()) {
            return Err(input(format!(
                "depth_threshold = {} must be positive and finite",
                opts.depth_threshold
            )));
        }
        if !(opts.min_footprint_px >= 0.0 && opts.min_footprint_px.is_finite()) {
            return Err(input(format!(
                "min_footprint_px = {} must be finite and ≥ 0",
                opts.min_footprint_px
            )));
        }
        let support = kernel.support_mm.max(kernel.radius_mm()) as f32;
        if !(support.is_finite() && support * opts.depth_threshold < f32::INFINITY) {
            return Err(input(format!("kernel support {support} mm is not finite")));
        }
        let total = kernel.total_weight();
        let taps = ShaderTaps::new(kernel, total, Energy::TotalReflectance);
        // A rank-1 export is a(x) a(y) with Σa = R: the vertical pass divides by R.
        let vertical_scale: [f32; 4] = match taps {
            ShaderTaps::Rank1(_) => {
                let s = total.map(|r| if r > 0.0 { (1.0 / r) as f32 } else { 0.0 });
                [s[0], s[1], s[2], 1.0]
            }
            ShaderTaps::Terms(_) => [1.0; 4],
        };
        let n_terms = match &taps {
            ShaderTaps::Rank1(_) => 1,
            ShaderTaps::Terms(t) => t.len(),
        };
        let sources = (0..n_terms)
            .map(|k| shader::wgsl_pass(&taps, k))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| input(format!("cannot export the kernel: {e}")))?;

        let device = &gpu.device;
        let unfilterable = wgpu::TextureSampleType::Float { filterable: false };
        let layout = checked(device, "bind group layout", || {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("sss pass"),
                entries: &[
                    float_texture(unfilterable, 0),
                    float_texture(unfilterable, 1),
                    float_texture(wgpu::TextureSampleType::Uint, 2),
                    float_texture(unfilterable, 3),
                    wgpu::BindGroupLayoutEntry {
                        binding: 4,
                        visibility: wgpu::ShaderStages::COMPUTE,
                        ty: wgpu::BindingType::StorageTexture {
                            access: wgpu::StorageTextureAccess::WriteOnly,
                            format: wgpu::TextureFormat::Rgba32Float,
                            view_dimension: wgpu::TextureViewDimension::D2,
                        },
                        count: None,
                    },
                    wgpu::BindGroupLayoutEntry {
                        binding: 5,
                        visibility: wgpu::ShaderStages::COMPUTE,
                        ty: wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Uniform,
                            has_dynamic_offset: false,
                            min_binding_size: wgpu::BufferSize::new(32),
                        },
                        count: None,
                    },
                    float_texture(unfilterable, 6),
                ],
            })
        })?;
        let pipeline_layout = checked(device, "pipeline layout", || {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("sss pass"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            })
        })?;
        let mut terms = Vec::with_capacity(n_terms);
        for (k, source) in sources.iter().enumerate() {
            let module = checked(device, "the exported WGSL pass", || {
                device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("separable_sss.wgsl"),
                    source: wgpu::ShaderSource::Wgsl(source.as_str().into()),
                })
            })?;
            let pipeline = |entry: &str| {
                checked(device, entry, || {
                    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(entry),
                        layout: Some(&pipeline_layout),
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        cache: None,
                    })
                })
            };
            let base = Params {
                support_mm: support,
                depth_threshold: opts.depth_threshold,
                min_footprint_px: opts.min_footprint_px,
                accumulate: 0,
                out_scale: [1.0; 4],
            };
            let vertical = Params {
                accumulate: u32::from(k > 0),
                out_scale: vertical_scale,
                ..base
            };
            let params = checked(device, "parameters", || {
                [base, vertical].map(|p| {
                    let bytes = p.bytes();
                    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("sss params"),
                        size: bytes.len() as u64,
                        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    });
                    gpu.queue.write_buffer(&buffer, 0, &bytes);
                    buffer
                })
            })?;
            terms.push(Term {
                horizontal: pipeline("sss_horizontal")?,
                vertical: pipeline("sss_vertical")?,
                params,
            });
        }
        Ok(GpuFilter {
            device: gpu.device.clone(),
            queue: gpu.queue.clone(),
            max_texture_2d: gpu.max_texture_2d,
            layout,
            terms,
            sources,
            id: NEXT_FILTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        })
    }

    /// The WGSL source of each term's module (the example pass with the export pasted in).
    pub fn sources(&self) -> &[String] {
        &self.sources
    }

    /// Uploads `input` into textures and binds them for every pass: a [`GpuFrame`] that
    /// [`GpuFilter::run`] (of this filter only) filters as many times as asked. Errors if the buffers disagree with
    /// width × height, if the image is empty or larger than the adapter's textures, or if an
    /// irradiance value is not finite.
    pub fn upload(&self, input: &ScreenInput) -> Result<GpuFrame, GpuError> {
        input
            .validate()
            .map_err(|e| GpuError::Input(e.to_string()))?;
        let (w, h) = (input.width, input.height);
        if w == 0 || h == 0 {
            return Err(GpuError::Input(format!("the image is empty ({w}×{h})")));
        }
        let max = self.max_texture_2d as usize;
        if w > max || h > max {
            return Err(GpuError::Input(format!(
                "{w}×{h} exceeds the adapter's largest texture ({max}×{max})"
            )));
        }
        if let Some(i) = input
            .irradiance
            .iter()
            .position(|p| !p.iter().all(|v| v.is_finite()))
        {
            return Err(GpuError::Input(format!(
                "irradiance at pixel ({}, {}) is not finite",
                i % w,
                i / w
            )));
        }
        let (w32, h32) = (w as u32, h as u32);
        let size = wgpu::Extent3d {
            width: w32,
            height: h32,
            depth_or_array_layers: 1,
        };
        checked(&self.device, "uploading the frame", || {
            let device = &self.device;
            let texture = |label: &str, format, usage| {
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size,
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
            };
            let sampled = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
            let written = wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_SRC;
            use wgpu::TextureFormat as F;
            let irradiance = texture("irradiance", F::Rgba32Float, sampled);
            let depth = texture("depth", F::R32Float, sampled);
            let ids = texture("object ids", F::R32Uint, sampled);
            let mm = texture("mm per pixel", F::R32Float, sampled);
            let middle = texture("horizontal pass", F::Rgba32Float, written);
            let out = [
                texture("output 0", F::Rgba32Float, written),
                texture("output 1", F::Rgba32Float, written),
            ];
            let write = |t: &wgpu::Texture, bytes: &[u8], texel: u32| {
                self.queue.write_texture(
                    t.as_image_copy(),
                    bytes,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(w32 * texel),
                        rows_per_image: Some(h32),
                    },
                    size,
                )
            };
            let rgba: Vec<u8> = input
                .irradiance
                .iter()
                .flat_map(|p| [p[0], p[1], p[2], 0.0])
                .flat_map(f32::to_le_bytes)
                .collect();
            write(&irradiance, &rgba, RGBA32F);
            drop(rgba);
            let floats =
                |v: &[f32]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
            write(&depth, &floats(input.depth), 4);
            write(&mm, &floats(input.mm_per_pixel), 4);
            let ids_bytes: Vec<u8> = input.mask.iter().flat_map(|x| x.to_le_bytes()).collect();
            write(&ids, &ids_bytes, 4);

            let view = |t: &wgpu::Texture| t.create_view(&Default::default());
            let (irr_v, depth_v, ids_v, mm_v, mid_v) = (
                view(&irradiance),
                view(&depth),
                view(&ids),
                view(&mm),
                view(&middle),
            );
            let out_v = [view(&out[0]), view(&out[1])];
            let bind = |src: &wgpu::TextureView,
                        dst: &wgpu::TextureView,
                        prev: &wgpu::TextureView,
                        params: &wgpu::Buffer| {
                let tex = |binding, v| wgpu::BindGroupEntry {
                    binding,
                    resource: wgpu::BindingResource::TextureView(v),
                };
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("sss pass"),
                    layout: &self.layout,
                    entries: &[
                        tex(0, src),
                        tex(1, &depth_v),
                        tex(2, &ids_v),
                        tex(3, &mm_v),
                        tex(4, dst),
                        wgpu::BindGroupEntry {
                            binding: 5,
                            resource: params.as_entire_binding(),
                        },
                        tex(6, prev),
                    ],
                })
            };
            // Term k: irradiance → middle; middle (+ the other output) → output k mod 2.
            let bind_groups = self
                .terms
                .iter()
                .enumerate()
                .map(|(k, term)| {
                    let (dst, prev) = (&out_v[k % 2], &out_v[(k + 1) % 2]);
                    [
                        bind(&irr_v, &mid_v, prev, &term.params[0]),
                        bind(&mid_v, dst, prev, &term.params[1]),
                    ]
                })
                .collect();
            let row_bytes = (w32 * RGBA32F).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
                * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
            let readback = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("sss readback"),
                size: u64::from(row_bytes) * u64::from(h32),
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            let result = out[(self.terms.len() - 1) % 2].clone();
            GpuFrame {
                owner: self.id,
                width: w32,
                height: h32,
                bind_groups,
                result,
                readback,
                row_bytes,
                _textures: [irradiance, depth, ids, mm, middle],
                _out: out,
            }
        })
    }

    /// Errors unless `frame` was uploaded by this filter.
    fn owns(&self, frame: &GpuFrame) -> Result<(), GpuError> {
        if frame.owner == self.id {
            Ok(())
        } else {
            Err(GpuError::Input(
                "the frame was uploaded by another GpuFilter".into(),
            ))
        }
    }

    /// Records every pass over `frame` (horizontal then vertical, per term) into an encoder.
    fn encode(&self, frame: &GpuFrame, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("separable sss"),
            timestamp_writes: None,
        });
        let groups = (frame.width.div_ceil(8), frame.height.div_ceil(8));
        for (term, bind) in self.terms.iter().zip(&frame.bind_groups) {
            for (pipeline, group) in [(&term.horizontal, &bind[0]), (&term.vertical, &bind[1])] {
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(groups.0, groups.1, 1);
            }
        }
    }

    /// Filters `frame` on the GPU (every pass of every term) and waits until it is done. The
    /// result stays on the GPU ([`GpuFilter::read`] copies it back); this is the call the
    /// benchmark times.
    pub fn run(&self, frame: &GpuFrame) -> Result<(), GpuError> {
        self.owns(frame)?;
        checked(&self.device, "running the passes", || {
            let mut encoder = self
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("sss") });
            self.encode(frame, &mut encoder);
            self.queue.submit([encoder.finish()]);
        })?;
        wait(&self.device)
    }

    /// Copies the result of the last [`GpuFilter::run`] on `frame` back: width × height RGB
    /// pixels, row-major (the diffuse exitance, as [`sss_separable::screen_space::filter`]
    /// gives it).
    pub fn read(&self, frame: &GpuFrame) -> Result<Vec<[f32; 3]>, GpuError> {
        self.owns(frame)?;
        checked(&self.device, "reading the result back", || {
            let mut encoder = self
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("sss readback"),
                });
            encoder.copy_texture_to_buffer(
                frame.result.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &frame.readback,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(frame.row_bytes),
                        rows_per_image: Some(frame.height),
                    },
                },
                wgpu::Extent3d {
                    width: frame.width,
                    height: frame.height,
                    depth_or_array_layers: 1,
                },
            );
            self.queue.submit([encoder.finish()]);
        })?;
        let (sender, receiver) = std::sync::mpsc::channel();
        frame.readback.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = sender.send(r);
        });
        wait(&self.device)?;
        receiver
            .recv()
            .map_err(|_| GpuError::Device("the readback was never mapped".into()))?
            .map_err(|e| GpuError::Device(format!("mapping the readback: {}", one_line(e))))?;
        let (w, h) = (frame.width as usize, frame.height as usize);
        let mut out = Vec::with_capacity(w * h);
        {
            let view = frame
                .readback
                .get_mapped_range(..)
                .map_err(|e| GpuError::Device(format!("reading the readback: {}", one_line(e))))?;
            for row in view.chunks_exact(frame.row_bytes as usize) {
                for texel in row[..w * RGBA32F as usize].chunks_exact(RGBA32F as usize) {
                    let f = |c: usize| {
                        f32::from_le_bytes([
                            texel[4 * c],
                            texel[4 * c + 1],
                            texel[4 * c + 2],
                            texel[4 * c + 3],
                        ])
                    };
                    out.push([f(0), f(1), f(2)]);
                }
            }
        }
        frame.readback.unmap();
        if let Some(i) = out.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
            return Err(GpuError::Device(format!(
                "the GPU gave a non-finite value at pixel ({}, {})",
                i % w,
                i / w
            )));
        }
        Ok(out)
    }

    /// Uploads, filters and reads back `input` in one call: the GPU's counterpart of
    /// [`sss_separable::screen_space::filter`] with `jitter_radius` 0. An empty image gives
    /// an empty result.
    pub fn filter(&self, input: &ScreenInput) -> Result<Vec<[f32; 3]>, GpuError> {
        if input.width == 0 || input.height == 0 {
            input
                .validate()
                .map_err(|e| GpuError::Input(e.to_string()))?;
            return Ok(Vec::new());
        }
        let frame = self.upload(input)?;
        self.run(&frame)?;
        self.read(&frame)
    }
}

/// A frame's inputs on the GPU, the intermediate and output images, and the bind groups of
/// every pass ([`GpuFilter::upload`]).
#[derive(Debug)]
pub struct GpuFrame {
    /// The id of the filter that uploaded it (its bind groups hold that filter's parameters).
    owner: u64,
    width: u32,
    height: u32,
    bind_groups: Vec<[wgpu::BindGroup; 2]>,
    result: wgpu::Texture,
    readback: wgpu::Buffer,
    row_bytes: u32,
    _textures: [wgpu::Texture; 5],
    _out: [wgpu::Texture; 2],
}

impl GpuFrame {
    /// Width and height in pixels.
    pub fn size(&self) -> (usize, usize) {
        (self.width as usize, self.height as usize)
    }
}
