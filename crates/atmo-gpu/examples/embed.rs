//! atmo's sky inside a program of one's own: a plain winit + wgpu window that makes
//! its own device, draws its own ground (a lit plane into a depth buffer), and lets
//! atmo draw the sky where the depth buffer is still at the far plane, in the same
//! encoder and render pass, with no read-back.
//!
//! The ground is lit and hazed by the same atmosphere: the sun's irradiance and the
//! sky's on a horizontal surface from `atmo::sky::lighting::Lighting` (per sun), and the
//! aerial perspective (`T(d) L + S(d)`, the light lost and gained between the eye and
//! the ground) from atmo's froxels: `GpuAerial::prepare` records their compute pass into
//! the program's encoder, 32 columns x as many rows as keep them square x 32 slices,
//! again when the sun or the camera turns, writing two 3-D textures
//! (`AerialTextures`) the ground's shader samples at its pixel and distance.
//!
//! ```text
//! cargo run --release -p atmo-gpu --example embed
//! ```
//! Drag with the mouse to look around; Up and Down arrows move the sun.

use std::sync::Arc;

use atmo::sky::aerial::quadratic_slices;
use atmo::sky::lighting::{Lighting, LUMENS_PER_WATT};
use atmo::sky::{SkyModel, SkyPicture, SkySettings, View};
use atmo::view::{Camera, Fov, Sun};
use atmo::Atmosphere;
use atmo_gpu::sky::{
    AerialTextures, DepthTarget, GpuAerial, GpuSkyModel, SkyPass, SkyTarget, AERIAL_LIGHT_WGSL,
};
use atmo_gpu::Gpu;
use glam::Vec3;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, KeyEvent, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// The program's own ground: a 120 km square at y = 0 (flat: 60 km out the Earth's
/// curve would drop it 280 m), a checkered Lambert surface lit
/// by the sun and the sky, seen through the aerial perspective's froxels.
const GROUND: &str = "
struct Uniforms {
    clip_from_world: mat4x4<f32>,
    eye: vec4<f32>,
    to_sun: vec4<f32>,
    // Irradiance on a surface facing the sun, and the sky's on a horizontal one,
    // linear sRGB W m^-2.
    sun: vec4<f32>,
    sky: vec4<f32>,
    // x: the window's width, y: its height, z: the farthest slice, m, w: the slices.
    froxels: vec4<f32>,
    exposure: vec4<f32>,
}
@group(0) @binding(0) var<uniform> u: Uniforms;
@group(0) @binding(1) var transmittance: texture_3d<f32>;
@group(0) @binding(2) var inscatter: texture_3d<f32>;
@group(0) @binding(3) var linear: sampler;
struct Out { @builtin(position) clip: vec4<f32>, @location(0) world: vec3<f32> }
@vertex fn vertex(@builtin(vertex_index) i: u32) -> Out {
    let corners = array(vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
                        vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0));
    let world = vec3(corners[i].x * 60000.0, 0.0, corners[i].y * 60000.0);
    return Out(u.clip_from_world * vec4(world, 1.0), world);
}
@fragment fn fragment(in: Out) -> @location(0) vec4<f32> {
    // Fields 300 m across; where a pixel spans a field, their mean (no moire).
    let cell = (i32(floor(in.world.x / 300.0)) + i32(floor(in.world.z / 300.0))) & 1;
    let footprint = max(fwidth(in.world.x), fwidth(in.world.z)) / 300.0;
    let field = mix(select(0.08, 0.16, cell == 1), 0.12, clamp(footprint, 0.0, 1.0));
    let albedo = field * vec3(0.9, 1.0, 0.7);
    let light = u.sun.rgb * max(u.to_sun.y, 0.0) + u.sky.rgb;
    let radiance = albedo / 3.14159265 * light;
    // The froxels under this pixel at this distance (atmo-gpu's aerial_light).
    let d = distance(in.world, u.eye.xyz);
    let uv = in.clip.xy / u.froxels.xy;
    let air = aerial_light(transmittance, inscatter, linear, uv, d, u.froxels.z, u.froxels.w);
    return vec4((air.transmittance * radiance + air.inscatter) * u.exposure.x, 1.0);
}";

/// The froxels' columns over the window (rows: as many as keep them square) and
/// slices, and how far the last slice is, m: the ground's far corners are 85 km away.
const FROXEL_COLUMNS: u32 = 32;
const SLICES: usize = 32;
const FAR_M: f64 = 90_000.0;
/// The eye's height above the ground, m: a low flight, where the haze shows.
const EYE_M: f32 = 600.0;
/// The elevation rows of the froxels' marked rays.
const FROXEL_ROWS: usize = 512;

const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

struct Scene {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    device: wgpu::Device,
    queue: wgpu::Queue,
    depth: wgpu::TextureView,
    ground: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    ground_group: wgpu::BindGroup,
    /// atmo on this program's device.
    gpu: Gpu,
    sky: GpuSkyModel<SkyModel>,
    sky_pass: SkyPass,
    /// The aerial perspective's pass (its rays, sun-independent, uploaded once) and the
    /// froxels' textures (transmittance, in-scattered radiance) the ground reads.
    aerial: GpuAerial,
    froxels: AerialTextures,
    linear: wgpu::Sampler,
    /// The sun's and the sky's irradiance (linear sRGB W m^-2), and the sun's elevation
    /// they were made for.
    light: Option<(f64, [Vec3; 2])>,
    /// The sun, yaw and window size the froxels were made for.
    hazed_for: Option<(f64, f64, (u32, u32))>,
    sun_elevation_deg: f64,
    yaw_deg: f64,
    dragging: Option<f64>,
}

#[derive(Default)]
struct App(Option<Scene>);

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.0.is_none() {
            self.0 = Some(Scene::new(event_loop));
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(scene) = &mut self.0 else { return };
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                (scene.config.width, scene.config.height) = (size.width, size.height);
                scene.surface.configure(&scene.device, &scene.config);
                scene.depth = depth_view(&scene.device, &scene.config);
            }
            WindowEvent::RedrawRequested => scene.draw(),
            WindowEvent::KeyboardInput {
                event:
                    KeyEvent {
                        physical_key: PhysicalKey::Code(code),
                        state: ElementState::Pressed,
                        ..
                    },
                ..
            } => match code {
                KeyCode::ArrowUp => {
                    scene.sun_elevation_deg = (scene.sun_elevation_deg + 1.0).min(90.0)
                }
                KeyCode::ArrowDown => {
                    scene.sun_elevation_deg = (scene.sun_elevation_deg - 1.0).max(-10.0)
                }
                _ => {}
            },
            WindowEvent::MouseInput { state, .. } => {
                scene.dragging = (state == ElementState::Pressed).then_some(f64::NAN);
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some(last) = scene.dragging {
                    if last.is_finite() {
                        scene.yaw_deg += 0.2 * (position.x - last);
                    }
                    scene.dragging = Some(position.x);
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(scene) = &self.0 {
            scene.window.request_redraw();
        }
    }
}

/// atmo's froxel textures for a grid of `(columns, rows)` and [`SLICES`], and the
/// ground's bindings: its uniforms, the textures and their sampler.
fn froxel_bindings(
    gpu: &Gpu,
    ground: &wgpu::RenderPipeline,
    uniforms: &wgpu::Buffer,
    linear: &wgpu::Sampler,
    (columns, rows): (u32, u32),
) -> (AerialTextures, wgpu::BindGroup) {
    let froxels =
        AerialTextures::new(gpu, (columns, rows, SLICES as u32)).expect("the froxel textures");
    let views =
        [&froxels.transmittance, &froxels.inscatter].map(|t| t.create_view(&Default::default()));
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("ground"),
        layout: &ground.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&views[0]),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(&views[1]),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: wgpu::BindingResource::Sampler(linear),
            },
        ],
    });
    (froxels, group)
}

fn depth_view(device: &wgpu::Device, config: &wgpu::SurfaceConfiguration) -> wgpu::TextureView {
    device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("depth"),
            size: wgpu::Extent3d {
                width: config.width,
                height: config.height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&Default::default())
}

impl Scene {
    fn new(event_loop: &ActiveEventLoop) -> Scene {
        let attributes = Window::default_attributes().with_title("atmo in my own renderer");
        let window = Arc::new(event_loop.create_window(attributes).expect("a window"));
        // The program's own instance, adapter and device, as any wgpu program has;
        // atmo needs FLOAT32_BLENDABLE on it; the ground filters the f32 froxels.
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let surface = instance.create_surface(window.clone()).expect("a surface");
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .expect("an adapter");
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            required_features: wgpu::Features::FLOAT32_BLENDABLE
                | wgpu::Features::FLOAT32_FILTERABLE,
            ..Default::default()
        }))
        .expect("a device");
        let size = window.inner_size();
        let config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .expect("the adapter presents to the window");
        surface.configure(&device, &config);
        let gpu = Gpu::from_device(device.clone(), queue.clone(), adapter.get_info())
            .expect("atmo on this device");
        // The sky by the shell method seen from the eye; the maps are uploaded once.
        let model = SkyModel::new(&Atmosphere::earth(), &SkySettings::default(), EYE_M as f64)
            .expect("a model");
        let slices = quadratic_slices(SLICES, FAR_M);
        let rays = model
            .aerial_rays(FROXEL_ROWS, &slices)
            .expect("the aerial rays");
        let sky = GpuSkyModel::new(&gpu, model).expect("the sky on the GPU");
        let aerial = GpuAerial::new(&gpu, &sky, rays).expect("the aerial pass");
        // The sky's pass for this program's targets: the surface and its depth buffer.
        let target = SkyTarget {
            format: config.format,
            depth: Some(DepthTarget {
                format: DEPTH,
                reversed_z: false,
            }),
            samples: 1,
        };
        let mut sky_pass = SkyPass::new(&gpu, target).expect("the sky's pipeline");
        sky_pass.exposure = 0.05;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("ground"),
            source: wgpu::ShaderSource::Wgsl(format!("{AERIAL_LIGHT_WGSL}{GROUND}").into()),
        });
        let ground = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("ground"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vertex"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fragment"),
                compilation_options: Default::default(),
                targets: &[Some(config.format.into())],
            }),
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ground"),
            size: 160,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let linear = device.create_sampler(&wgpu::SamplerDescriptor {
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let (froxels, ground_group) = froxel_bindings(&gpu, &ground, &uniforms, &linear, (1, 1));
        Scene {
            depth: depth_view(&device, &config),
            window,
            surface,
            config,
            device,
            queue,
            ground,
            uniforms,
            ground_group,
            gpu,
            sky,
            sky_pass,
            aerial,
            froxels,
            linear,
            light: None,
            hazed_for: None,
            sun_elevation_deg: 8.0,
            yaw_deg: 180.0,
            dragging: None,
        }
    }

    fn draw(&mut self) {
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            _ => {
                self.surface.configure(&self.device, &self.config);
                return;
            }
        };
        let target = texture.texture.create_view(&Default::default());
        let size = (self.config.width, self.config.height);
        // One camera for both: the program's matrices and atmo's view of the same eye.
        let eye = Vec3::new(0.0, EYE_M, 0.0);
        let yaw = self.yaw_deg.to_radians() as f32;
        let forward = Vec3::new(yaw.sin(), -0.1, -yaw.cos()).normalize();
        let fov_deg = 60.0f32;
        let camera = Camera::look_at(eye, eye + forward, Vec3::Y, Fov::Vertical(fov_deg), size)
            .expect("a camera");
        let aspect = size.0 as f32 / size.1 as f32;
        let clip_from_world = glam::camera::rh::proj::directx::perspective(
            fov_deg.to_radians(),
            aspect,
            1.0,
            200_000.0,
        ) * glam::camera::rh::view::look_to_mat4(eye, forward, Vec3::Y);
        let sun = Sun::from_degrees(self.sun_elevation_deg, 180.0).expect("a sun");
        let [sunlight, skylight] = self.light(sun);
        let mut encoder = self.device.create_command_encoder(&Default::default());
        // atmo records the froxels into the program's encoder when the sun or the view
        // turned...
        if self.hazed_for != Some((self.sun_elevation_deg, self.yaw_deg, size)) {
            self.hazed_for = Some((self.sun_elevation_deg, self.yaw_deg, size));
            self.haze(&mut encoder, sun, eye, forward, fov_deg);
        }
        let to_sun = sun.toward();
        let mut uniforms = clip_from_world.to_cols_array().to_vec();
        uniforms.extend([eye.x, eye.y, eye.z, 0.0]);
        uniforms.extend([to_sun.x, to_sun.y, to_sun.z, 0.0]);
        uniforms.extend([sunlight.x, sunlight.y, sunlight.z, 0.0]);
        uniforms.extend([skylight.x, skylight.y, skylight.z, 0.0]);
        let (w, h) = (size.0 as f32, size.1 as f32);
        uniforms.extend([w, h, FAR_M as f32, SLICES as f32]);
        uniforms.extend([self.sky_pass.exposure, 0.0, 0.0, 0.0]);
        self.queue
            .write_buffer(&self.uniforms, 0, bytemuck::cast_slice(&uniforms));
        // ... and this sun's maps...
        let view = View {
            camera,
            sun_disc: true,
        };
        self.sky
            .prepare(&self.gpu, &mut encoder, &mut self.sky_pass, sun, &view)
            .expect("the sky's maps");
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("the frame"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            // ... the program draws its ground ...
            pass.set_pipeline(&self.ground);
            pass.set_bind_group(0, &self.ground_group, &[]);
            pass.draw(0..6, 0..1);
            // ... and atmo's sky fills what the ground left at the far plane.
            self.sky_pass.draw(&mut pass);
        }
        self.queue.submit([encoder.finish()]);
        self.window.pre_present_notify();
        self.queue.present(texture);
    }

    /// The ground's light for `sun`: the sun's irradiance on a surface facing it and
    /// the sky's on a horizontal one, made again only when the sun has moved.
    fn light(&mut self, sun: Sun) -> [Vec3; 2] {
        let elevation = self.sun_elevation_deg;
        if let Some((made_for, light)) = self.light {
            if made_for == elevation {
                return light;
            }
        }
        let model = self.sky.model();
        let lighting = Lighting::new(
            &SkyPicture::new(model, sun),
            model.atmosphere(),
            model.altitude_m(),
            sun,
        );
        let sunlight = Vec3::from(lighting.sun.colour.map(|c| c as f32))
            * (lighting.sun.normal_lux / LUMENS_PER_WATT) as f32;
        let skylight = Vec3::from(lighting.sky_irradiance_up.map(|c| c as f32));
        self.light = Some((elevation, [sunlight, skylight]));
        [sunlight, skylight]
    }

    /// Records into `encoder` the aerial perspective's froxels over the window for `sun`
    /// and an eye at `eye` looking along `forward` with a vertical field of `fov_deg`.
    fn haze(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        sun: Sun,
        eye: Vec3,
        forward: Vec3,
        fov_deg: f32,
    ) {
        // A froxel camera of the window's aspect: as many rows as keep its pixels square.
        let (w, h) = (self.config.width as f32, self.config.height as f32);
        let columns = FROXEL_COLUMNS;
        let rows = ((columns as f32 * h / w).round() as u32).clamp(1, 4 * columns);
        if self.froxels.size.1 != rows {
            (self.froxels, self.ground_group) = froxel_bindings(
                &self.gpu,
                &self.ground,
                &self.uniforms,
                &self.linear,
                (columns, rows),
            );
        }
        let camera = Camera::look_at(
            eye,
            eye + forward,
            Vec3::Y,
            Fov::Vertical(fov_deg),
            (columns, rows),
        )
        .expect("a froxel camera");
        self.aerial
            .prepare(&self.gpu, encoder, &self.sky, sun, &camera, &self.froxels)
            .expect("the froxels");
    }
}

fn main() {
    let event_loop = EventLoop::new().expect("a display (DISPLAY or WAYLAND_DISPLAY)");
    event_loop
        .run_app(&mut App::default())
        .expect("the event loop");
}
