//! The device every pipeline runs on: adapter selection, the features and limits atmo
//! needs checked up front, and submissions that turn GPU errors (out of memory, a lost
//! device) into [`GpuError`]s instead of panics.

use std::io::Write as _;
use std::sync::{Arc, Mutex};

use wgpu::util::DeviceExt;

use crate::GpuError;

/// Features every pipeline needs: additive blending into f32 targets (shafts' planes,
/// clouds' billboards accumulate in f32; f16 loses 4 % over 180 quads on lavapipe).
const REQUIRED_FEATURES: &[(wgpu::Features, &str)] = &[(
    wgpu::Features::FLOAT32_BLENDABLE,
    "float32 blending (additive planes and billboards in f32 targets)",
)];

/// What a render pipeline draws into: its colour targets, the depth buffer it tests
/// against, and the samples a pixel of both (1 without multisampling).
struct Attachments<'t> {
    colour: &'t [Option<wgpu::ColorTargetState>],
    depth: Option<wgpu::DepthStencilState>,
    samples: u32,
}

/// A device and queue, with what is known of the adapter behind them. A clone is the
/// same device (wgpu's handles are shared).
#[derive(Clone)]
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// The adapter's name, backend and kind.
    pub info: wgpu::AdapterInfo,
    /// Whether passes can be timed with timestamp queries.
    pub timestamps: bool,
    /// Why the device was lost, once it is.
    lost: Arc<Mutex<Option<String>>>,
}

impl Gpu {
    /// Opens an adapter: `choice` matches an adapter's name (any part, any case) or a
    /// backend (`vulkan`, `metal`, `dx12`); without it, `WGPU_ADAPTER_NAME` does, and
    /// else the first of discrete, integrated, virtual, software. The instance follows
    /// `WGPU_BACKEND` and the drivers' own variables (`VK_DRIVER_FILES`).
    pub fn new(choice: Option<&str>) -> Result<Gpu, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = choose_adapter(&instance, choice, None)?;
        Gpu::open(&adapter)
    }

    /// Opens a device on `adapter` with the features atmo needs (refused by name where
    /// the adapter lacks one), timestamps where it has them, and the adapter's own limits.
    pub fn open(adapter: &wgpu::Adapter) -> Result<Gpu, GpuError> {
        let info = adapter.get_info();
        let features = adapter.features();
        missing_feature(features, &info)?;
        let mut required = wgpu::Features::FLOAT32_BLENDABLE;
        if features.contains(TIMING) {
            required |= TIMING;
        }
        // The adapter's own limits: the largest buffers and 3-D textures it has, which
        // `check_limit` compares requests against before anything is allocated.
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("atmo"),
            required_features: required,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        let gpu = Gpu::from_device(device, queue, info)?;
        let on_lost = gpu.lost.clone();
        gpu.device.set_device_lost_callback(move |reason, message| {
            *on_lost.lock().unwrap() = Some(format!("{reason:?}: {message}"));
        });
        // Errors outside a `run` scope (none are expected) are reported, not panicked on.
        gpu.device.on_uncaptured_error(Arc::new(|e| {
            // Never a panic where standard error fails: the message is lost.
            let _ = writeln!(std::io::stderr(), "atmo-gpu: {e}");
        }));
        Ok(gpu)
    }

    /// atmo on a device the caller made (its own renderer's): the device must have
    /// `FLOAT32_BLENDABLE` (refused by name otherwise); passes are timed where it has
    /// `TIMESTAMP_QUERY` and `TIMESTAMP_QUERY_INSIDE_ENCODERS`. The caller's device-lost
    /// and uncaptured-error callbacks are left as they are. `Device` and `Queue` are
    /// handles: pass clones of the caller's.
    pub fn from_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
        info: wgpu::AdapterInfo,
    ) -> Result<Gpu, GpuError> {
        let features = device.features();
        missing_feature(features, &info)?;
        Ok(Gpu {
            device,
            queue,
            info,
            timestamps: features.contains(TIMING),
            lost: Arc::new(Mutex::new(None)),
        })
    }

    /// One line naming the device, for the CLI's notice.
    pub fn describe(&self) -> String {
        describe(&self.info)
    }

    /// Whether the adapter is a software rasteriser (llvmpipe and the like).
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// The device's limits (the adapter's).
    pub fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }

    /// Refuses `needed` above the device's `limit` named `limit_name`, before any
    /// allocation: `what` is the resource, `setting` what to lower.
    pub fn check_limit(
        &self,
        what: &str,
        needed: u64,
        limit: u64,
        limit_name: &str,
        setting: &str,
    ) -> Result<(), GpuError> {
        if needed > limit {
            return Err(GpuError::OverLimit {
                what: what.to_string(),
                needed,
                limit: limit_name.to_string(),
                max: limit,
                setting: setting.to_string(),
            });
        }
        Ok(())
    }

    /// A storage buffer of `contents` (an empty one 256 zero bytes: room for a record),
    /// checked against the device's binding limit.
    pub fn storage(
        &self,
        label: &str,
        contents: &[u8],
        setting: &str,
    ) -> Result<wgpu::Buffer, GpuError> {
        let limit = self.limits().max_storage_buffer_binding_size;
        self.check_limit(
            label,
            contents.len() as u64,
            limit,
            "max_storage_buffer_binding_size",
            setting,
        )?;
        // A shader's runtime-sized array is bound with room for one element at least:
        // an empty one gets 256 zero bytes, more than any of atmo's records.
        let zero = [0u8; 256];
        let contents = if contents.is_empty() {
            &zero[..]
        } else {
            contents
        };
        Ok(self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
            }))
    }

    /// A 2-D texture of `width` x `height` in `format` for `usage` (one mip level, one
    /// sample): the pictures, targets, tables and layers atmo's passes make.
    pub fn texture_2d(
        &self,
        label: &str,
        (width, height): (u32, u32),
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> wgpu::Texture {
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    }

    /// An R32 float texture of `width` x `rows` holding `values` row after row, for
    /// shaders to sample (`label` names it in the device's messages).
    pub fn float_texture(
        &self,
        label: &str,
        values: &[f32],
        width: u32,
        rows: u32,
    ) -> wgpu::Texture {
        let size = wgpu::Extent3d {
            width,
            height: rows,
            depth_or_array_layers: 1,
        };
        let texture = self.texture_2d(
            label,
            (width, rows),
            wgpu::TextureFormat::R32Float,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        self.queue.write_texture(
            texture.as_image_copy(),
            bytemuck::cast_slice(values),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(width * 4),
                rows_per_image: None,
            },
            size,
        );
        texture
    }

    /// Refuses a 2-D texture side `side` above the device's `max_texture_dimension_2d`.
    pub fn check_texture_side(&self, what: &str, side: u32, setting: &str) -> Result<(), GpuError> {
        let max = self.limits().max_texture_dimension_2d;
        self.check_limit(
            what,
            side as u64,
            max as u64,
            "max_texture_dimension_2d",
            setting,
        )
    }

    /// A storage buffer the GPU writes (and the CPU may read back), checked against the
    /// binding limit before it is allocated.
    pub fn output(&self, what: &str, bytes: u64, setting: &str) -> Result<wgpu::Buffer, GpuError> {
        let limits = self.limits();
        self.check_limit(
            what,
            bytes,
            limits.max_storage_buffer_binding_size,
            "max_storage_buffer_binding_size",
            setting,
        )?;
        Ok(self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(what),
            size: bytes.max(4),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        }))
    }

    /// Writes `bytes` into `buffer` at `offset` in `encoder`'s order (a copy from a
    /// staged buffer), where `queue.write_buffer` writes before the whole submission
    /// runs: what one eye's passes set then stays theirs when another eye's passes,
    /// recorded after them into the same submission, set their own.
    pub fn write_recorded(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        buffer: &wgpu::Buffer,
        offset: u64,
        bytes: &[u8],
    ) {
        let staged = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("staged for an ordered write"),
                contents: bytes,
                usage: wgpu::BufferUsages::COPY_SRC,
            });
        encoder.copy_buffer_to_buffer(&staged, 0, buffer, offset, bytes.len() as u64);
    }

    /// A uniform buffer holding `value`.
    pub fn uniform<T: bytemuck::Pod>(&self, label: &str, value: &T) -> wgpu::Buffer {
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::bytes_of(value),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            })
    }

    /// A shader module from WGSL source; a shader the device refuses is an error.
    pub fn shader(&self, name: &str, source: &str) -> Result<wgpu::ShaderModule, GpuError> {
        self.scoped(name, || {
            self.device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(name),
                    source: wgpu::ShaderSource::Wgsl(source.into()),
                })
        })
    }

    /// A compute pipeline of `entry` in `module`, with `layout` or, without one, the
    /// layout inferred from the shader.
    pub fn compute_pipeline(
        &self,
        module: &wgpu::ShaderModule,
        entry: &str,
        layout: Option<&wgpu::PipelineLayout>,
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        self.scoped(entry, || {
            self.device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout,
                    module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                })
        })
    }

    /// A render pipeline drawing `vertex` and `fragment` of `module` (no vertex
    /// buffers) into `targets` RGBA f32 targets with `blend`, e.g. additive planes or
    /// premultiplied "over" billboards.
    pub fn blended_pipeline(
        &self,
        module: &wgpu::ShaderModule,
        layout: Option<&wgpu::PipelineLayout>,
        blend: wgpu::BlendComponent,
        targets: usize,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        self.blended_pipeline_of("fragment", module, layout, blend, targets)
    }

    /// [`Gpu::blended_pipeline`] with the fragment shader `fragment` of `module`.
    pub fn blended_pipeline_of(
        &self,
        fragment: &str,
        module: &wgpu::ShaderModule,
        layout: Option<&wgpu::PipelineLayout>,
        blend: wgpu::BlendComponent,
        targets: usize,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let target = wgpu::ColorTargetState {
            format: wgpu::TextureFormat::Rgba32Float,
            blend: Some(wgpu::BlendState {
                color: blend,
                alpha: blend,
            }),
            write_mask: wgpu::ColorWrites::ALL,
        };
        let targets = vec![Some(target); targets];
        let attachments = Attachments {
            colour: &targets,
            depth: None,
            samples: 1,
        };
        self.pipeline("a render pipeline", module, fragment, layout, attachments)
    }

    /// A render pipeline drawing `vertex` and `fragment` of `module` (no vertex
    /// buffers, triangles) into the colour `targets` of `samples` samples a pixel (1
    /// without multisampling), depth-tested by `depth` where given; refused as a
    /// [`GpuError`] naming `what` where the device cannot make it.
    pub fn screen_pipeline(
        &self,
        what: &str,
        module: &wgpu::ShaderModule,
        layout: Option<&wgpu::PipelineLayout>,
        targets: &[Option<wgpu::ColorTargetState>],
        depth: Option<wgpu::DepthStencilState>,
        samples: u32,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let attachments = Attachments {
            colour: targets,
            depth,
            samples,
        };
        self.pipeline(what, module, "fragment", layout, attachments)
    }

    /// [`Gpu::screen_pipeline`] with the fragment shader `fragment` of `module`.
    fn pipeline(
        &self,
        what: &str,
        module: &wgpu::ShaderModule,
        fragment: &str,
        layout: Option<&wgpu::PipelineLayout>,
        attachments: Attachments,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        self.scoped(what, || {
            self.device
                .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(what),
                    layout,
                    vertex: wgpu::VertexState {
                        module,
                        entry_point: Some("vertex"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    fragment: Some(wgpu::FragmentState {
                        module,
                        entry_point: Some(fragment),
                        compilation_options: Default::default(),
                        targets: attachments.colour,
                    }),
                    primitive: Default::default(),
                    depth_stencil: attachments.depth,
                    multisample: wgpu::MultisampleState {
                        count: attachments.samples,
                        ..Default::default()
                    },
                    multiview_mask: None,
                    cache: None,
                })
        })
    }

    /// A bind group of `resources` (binding `i` gets entry `i`) for group 0 of `layout`.
    pub fn bind_group(
        &self,
        layout: &wgpu::BindGroupLayout,
        resources: &[wgpu::BindingResource],
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = resources
            .iter()
            .enumerate()
            .map(|(i, r)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: r.clone(),
            })
            .collect();
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout,
            entries: &entries,
        })
    }

    /// Records commands with `record`, submits them and waits: out-of-memory and
    /// validation errors come back as [`GpuError`]s naming `what`, as does a lost device.
    /// Where the adapter has timestamp queries, returns the GPU time between the start
    /// and the end of the commands, ms.
    pub fn run(
        &self,
        what: &str,
        record: impl FnOnce(&mut wgpu::CommandEncoder),
    ) -> Result<Option<f64>, GpuError> {
        let resolved = self.scoped(what, || self.submit(what, record))??;
        match resolved {
            Some(buffer) => {
                let bytes = self.read(what, &buffer, 0, 16)?;
                let ticks: &[u64] = bytemuck::cast_slice(&bytes);
                let period = self.queue.get_timestamp_period() as f64;
                Ok(Some(
                    ticks[1].saturating_sub(ticks[0]) as f64 * period * 1e-6,
                ))
            }
            None => Ok(None),
        }
    }

    /// Runs `make` (resource and pipeline creation, submissions) with out-of-memory and
    /// validation errors caught and returned as [`GpuError`]s naming `what`.
    pub fn scoped<T>(&self, what: &str, make: impl FnOnce() -> T) -> Result<T, GpuError> {
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = make();
        let errors = [
            pollster::block_on(validation.pop()),
            pollster::block_on(memory.pop()),
        ];
        if let Some(e) = errors.into_iter().flatten().next() {
            return Err(match e {
                wgpu::Error::OutOfMemory { .. } => GpuError::OutOfMemory(what.to_string()),
                other => GpuError::Internal {
                    what: what.to_string(),
                    message: other.to_string(),
                },
            });
        }
        Ok(value)
    }

    /// Records, submits and waits; the timestamps' resolve buffer, where there is one.
    fn submit(
        &self,
        what: &str,
        record: impl FnOnce(&mut wgpu::CommandEncoder),
    ) -> Result<Option<wgpu::Buffer>, GpuError> {
        let queries = self.timestamps.then(|| {
            self.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            })
        });
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(what) });
        if let Some(q) = &queries {
            encoder.write_timestamp(q, 0);
        }
        record(&mut encoder);
        let resolved = queries.as_ref().map(|q| {
            encoder.write_timestamp(q, 1);
            let resolve = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            encoder.resolve_query_set(q, 0..2, &resolve, 0);
            resolve
        });
        self.queue.submit([encoder.finish()]);
        self.wait(what)?;
        Ok(resolved)
    }

    /// Waits for the queue; a lost device or a timeout is an error.
    fn wait(&self, what: &str) -> Result<(), GpuError> {
        let waited = self.device.poll(wgpu::PollType::wait_indefinitely());
        if let Some(reason) = self.lost.lock().unwrap().clone() {
            return Err(GpuError::DeviceLost {
                what: what.to_string(),
                reason,
            });
        }
        waited.map(|_| ()).map_err(|e| GpuError::DeviceLost {
            what: what.to_string(),
            reason: e.to_string(),
        })
    }

    /// Copies `size` bytes at `offset` of `buffer` (which has `COPY_SRC`) back.
    pub fn read(
        &self,
        what: &str,
        buffer: &wgpu::Buffer,
        offset: u64,
        size: u64,
    ) -> Result<Vec<u8>, GpuError> {
        self.read_with(what, buffer, offset, size, <[u8]>::to_vec)
    }

    /// `use_bytes` of the `size` bytes at `offset` of `buffer` (which has `COPY_SRC`),
    /// as the device maps them back: no copy of them is made on the way.
    pub fn read_with<T>(
        &self,
        what: &str,
        buffer: &wgpu::Buffer,
        offset: u64,
        size: u64,
        use_bytes: impl FnOnce(&[u8]) -> T,
    ) -> Result<T, GpuError> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(what) });
        encoder.copy_buffer_to_buffer(buffer, offset, &staging, 0, size);
        self.queue.submit([encoder.finish()]);
        self.mapped(what, &staging, use_bytes)
    }

    /// `use_bytes` of the whole of `buffer` (which has `MAP_READ`, its copies
    /// submitted), mapped; unmapped after.
    fn mapped<T>(
        &self,
        what: &str,
        buffer: &wgpu::Buffer,
        use_bytes: impl FnOnce(&[u8]) -> T,
    ) -> Result<T, GpuError> {
        let slice = buffer.slice(..);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = sender.send(r);
        });
        self.wait(what)?;
        match receiver.recv() {
            Ok(Ok(())) => {}
            Ok(Err(e)) => {
                return Err(GpuError::Internal {
                    what: what.to_string(),
                    message: e.to_string(),
                })
            }
            Err(_) => {
                return Err(GpuError::DeviceLost {
                    what: what.to_string(),
                    reason: "the read-back never completed".into(),
                })
            }
        }
        let value = use_bytes(&slice.get_mapped_range().map_err(|e| GpuError::Internal {
            what: what.to_string(),
            message: e.to_string(),
        })?);
        buffer.unmap();
        Ok(value)
    }

    /// Copies an RGBA f32 texture of `width` x `height` back, rows unpadded.
    pub fn read_texture(
        &self,
        what: &str,
        texture: &wgpu::Texture,
        width: u32,
        height: u32,
    ) -> Result<Vec<u8>, GpuError> {
        self.read_texture_layers(what, texture, (width, height, 1))
    }

    /// An RGBA f32 texture of `width` x `height` read back as a frame (its alpha left
    /// out), straight from the mapped rows: the picture's only copies are the
    /// texture, the read-back buffer and the frame ([`PICTURE_BYTES_PER_PIXEL`]).
    pub fn read_frame(
        &self,
        what: &str,
        texture: &wgpu::Texture,
        (width, height): (u32, u32),
    ) -> Result<atmo::image::Frame, GpuError> {
        let mut frame = atmo::image::Frame::new(width, height);
        let mut rows = frame.pixels.chunks_mut(width as usize);
        self.read_texture_rows(
            what,
            texture,
            wgpu::Origin3d::ZERO,
            (width, height, 1),
            |row| {
                let pixels = rows.next().expect("one row of the frame a row read");
                crate::rgb_of(row, pixels);
            },
        )?;
        Ok(frame)
    }

    /// Copies a texture of `width` x `height` x `depth` (a 3-D texture's slices, or
    /// layers; an uncompressed format, RGBA f32 for atmo's pictures) back, rows
    /// unpadded, slice after slice.
    pub fn read_texture_layers(
        &self,
        what: &str,
        texture: &wgpu::Texture,
        size: (u32, u32, u32),
    ) -> Result<Vec<u8>, GpuError> {
        self.read_texture_region(what, texture, wgpu::Origin3d::ZERO, size)
    }

    /// Copies the `width` x `height` x `depth` texels of a texture from `origin` back
    /// (an uncompressed format), rows unpadded, slice after slice: a part of a
    /// picture without the rest's copy.
    pub fn read_texture_region(
        &self,
        what: &str,
        texture: &wgpu::Texture,
        origin: wgpu::Origin3d,
        size: (u32, u32, u32),
    ) -> Result<Vec<u8>, GpuError> {
        let texel = texture.format().block_copy_size(None).unwrap_or(16) as usize;
        let mut bytes =
            Vec::with_capacity(texel * size.0 as usize * size.1 as usize * size.2 as usize);
        self.read_texture_rows(what, texture, origin, size, |row| {
            bytes.extend_from_slice(row)
        })?;
        Ok(bytes)
    }

    /// Each row of the `width` x `height` x `depth` texels of a texture from `origin`
    /// (an uncompressed format), slice after slice, given to `each_row` as the mapped
    /// read-back holds it (the texture is copied into a mappable buffer directly).
    fn read_texture_rows(
        &self,
        what: &str,
        texture: &wgpu::Texture,
        origin: wgpu::Origin3d,
        (width, height, depth): (u32, u32, u32),
        mut each_row: impl FnMut(&[u8]),
    ) -> Result<(), GpuError> {
        let texel = texture.format().block_copy_size(None).unwrap_or(16);
        let row = width as u64 * texel as u64;
        let padded = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as u64);
        let rows = height as u64 * depth as u64;
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(what),
            size: padded * rows,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.run(what, |encoder| {
            encoder.copy_texture_to_buffer(
                wgpu::TexelCopyTextureInfo {
                    origin,
                    ..texture.as_image_copy()
                },
                wgpu::TexelCopyBufferInfo {
                    buffer: &buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(padded as u32),
                        rows_per_image: Some(height),
                    },
                },
                wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: depth,
                },
            );
        })?;
        self.mapped(what, &buffer, |bytes| {
            for r in bytes.chunks(padded as usize) {
                each_row(&r[..row as usize]);
            }
        })
    }

    /// Refuses a `width` x `height` picture whose copies on the device and back
    /// ([`PICTURE_BYTES_PER_PIXEL`]) are past the run's memory budget
    /// ([`atmo::budget`]): on a software driver the device's memory is the process's.
    pub fn check_picture(
        &self,
        what: &str,
        (width, height): (u32, u32),
        setting: &str,
    ) -> Result<(), GpuError> {
        atmo::budget::check(
            &format!("{what} ({width} x {height}) on the GPU"),
            width as u64 * height as u64 * PICTURE_BYTES_PER_PIXEL,
            setting,
        )?;
        Ok(())
    }
}

/// What a picture rendered on the GPU and read back holds a pixel, bytes: the RGBA f32
/// target (16), the mapped read-back (16) and the frame (12), on a software driver
/// all of them the process's memory. Measured from outside at 44 (peak resident size
/// over 12.6 M more pixels of `atmo sky --backend gpu` on llvmpipe; 64 while the
/// read-back went through two more copies); charged at 48.
pub const PICTURE_BYTES_PER_PIXEL: u64 = 48;

/// Timestamps between the passes of one encoder.
const TIMING: wgpu::Features =
    wgpu::Features::TIMESTAMP_QUERY.union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);

/// The first of [`REQUIRED_FEATURES`] that `features` lacks, as an error.
fn missing_feature(features: wgpu::Features, info: &wgpu::AdapterInfo) -> Result<(), GpuError> {
    match REQUIRED_FEATURES
        .iter()
        .find(|(f, _)| !features.contains(*f))
    {
        Some((_, why)) => Err(GpuError::MissingFeature {
            adapter: describe(info),
            missing: why.to_string(),
        }),
        None => Ok(()),
    }
}

/// Why no adapter was found, from the variables `var` reads: `WGPU_BACKEND` or the
/// Vulkan loader's driver list pointing nowhere, else no driver installed.
fn no_adapter_hint(var: impl Fn(&str) -> Option<String>) -> String {
    if let Some(backends) = var("WGPU_BACKEND") {
        return format!(
            "WGPU_BACKEND={backends} leaves out every backend with an adapter here; unset it \
             or name another (vulkan, metal, dx12)"
        );
    }
    for name in ["VK_DRIVER_FILES", "VK_ICD_FILENAMES"] {
        if let Some(files) = var(name) {
            let sep = if cfg!(windows) { ';' } else { ':' };
            return match files
                .split(sep)
                .find(|f| !f.is_empty() && !std::path::Path::new(f).exists())
            {
                Some(missing) => format!("{name} names {missing}, which does not exist; unset it"),
                None => format!("the drivers {name}={files} names found no device; unset it"),
            };
        }
    }
    "install mesa-vulkan-drivers for a software one".to_string()
}

/// The adapter of `instance` that `choice` names (see [`Gpu::new`]), among those that
/// can present to `surface` where one is given (a window's).
pub fn choose_adapter(
    instance: &wgpu::Instance,
    choice: Option<&str>,
    surface: Option<&wgpu::Surface>,
) -> Result<wgpu::Adapter, GpuError> {
    let adapters: Vec<wgpu::Adapter> =
        pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
            .into_iter()
            .filter(|a| surface.is_none_or(|s| a.is_surface_supported(s)))
            .collect();
    if adapters.is_empty() {
        return Err(GpuError::NoAdapter {
            hint: no_adapter_hint(|name| std::env::var(name).ok()),
        });
    }
    let wanted = choice
        .map(str::to_owned)
        .or_else(|| std::env::var("WGPU_ADAPTER_NAME").ok())
        .map(|s| s.to_lowercase());
    let matches = |a: &wgpu::Adapter| {
        let info = a.get_info();
        wanted.as_ref().is_none_or(|w| {
            info.name.to_lowercase().contains(w.as_str())
                || info.backend.to_str().eq_ignore_ascii_case(w)
        })
    };
    let rank = |a: &wgpu::Adapter| match a.get_info().device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    };
    let names: Vec<String> = adapters.iter().map(|a| describe(&a.get_info())).collect();
    adapters
        .into_iter()
        .filter(matches)
        .min_by_key(rank)
        .ok_or_else(|| GpuError::NoMatch {
            wanted: wanted.unwrap_or_default(),
            found: names.join("; "),
        })
}

fn describe(info: &wgpu::AdapterInfo) -> String {
    let kind = match info.device_type {
        wgpu::DeviceType::Cpu => "software",
        wgpu::DeviceType::DiscreteGpu => "discrete",
        wgpu::DeviceType::IntegratedGpu => "integrated",
        wgpu::DeviceType::VirtualGpu => "virtual",
        wgpu::DeviceType::Other => "other",
    };
    format!("{} ({:?}, {kind})", info.name, info.backend)
}

#[cfg(test)]
mod tests {
    use super::no_adapter_hint;

    #[test]
    fn the_hint_names_the_variable_that_hides_the_drivers() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |name: &str| {
                pairs
                    .iter()
                    .find(|(n, _)| *n == name)
                    .map(|(_, v)| v.to_string())
            }
        };
        assert!(no_adapter_hint(env(&[("WGPU_BACKEND", "dx12")])).starts_with("WGPU_BACKEND=dx12"));
        let hint = no_adapter_hint(env(&[("VK_DRIVER_FILES", "/nowhere/icd.json")]));
        assert!(
            hint.contains("VK_DRIVER_FILES names /nowhere/icd.json, which does not exist"),
            "{hint}"
        );
        assert!(no_adapter_hint(env(&[])).contains("mesa-vulkan-drivers"));
    }
}
