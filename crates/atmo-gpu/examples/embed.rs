//! atmo's sky inside a program of one's own: a plain winit + wgpu window that makes
//! its own device, draws its own ground (a lit plane into a depth buffer), and lets
//! atmo draw the sky where the depth buffer is still at the far plane, in the same
//! encoder and render pass, with no read-back.
//!
//! ```text
//! cargo run --release -p atmo-gpu --example embed
//! ```
//! Drag with the mouse to look around; Up and Down arrows move the sun.

use std::sync::Arc;

use atmo::sky::{SkyModel, SkySettings, View};
use atmo::view::{Camera, Fov, Sun};
use atmo::Atmosphere;
use atmo_gpu::sky::{DepthTarget, GpuSkyModel, SkyPass, SkyTarget};
use atmo_gpu::Gpu;
use glam::{Mat4, Vec3};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, KeyEvent, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// The program's own ground: a 40 km square at y = 0, lit by the sun (Lambert).
const GROUND: &str = "
struct Uniforms { clip_from_world: mat4x4<f32>, to_sun: vec4<f32> }
@group(0) @binding(0) var<uniform> u: Uniforms;
struct Out { @builtin(position) clip: vec4<f32>, @location(0) world: vec3<f32> }
@vertex fn vertex(@builtin(vertex_index) i: u32) -> Out {
    let corners = array(vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
                        vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0));
    let world = vec3(corners[i].x * 20000.0, 0.0, corners[i].y * 20000.0);
    return Out(u.clip_from_world * vec4(world, 1.0), world);
}
@fragment fn fragment(in: Out) -> @location(0) vec4<f32> {
    let cell = (i32(floor(in.world.x / 5.0)) + i32(floor(in.world.z / 5.0))) & 1;
    let albedo = select(0.10, 0.16, cell == 1);
    let light = max(u.to_sun.y, 0.0) * 1.2 + 0.15;
    return vec4(vec3(albedo * light * 0.9, albedo * light, albedo * light * 0.7), 1.0);
}";

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
        // atmo needs FLOAT32_BLENDABLE on it.
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
            required_features: wgpu::Features::FLOAT32_BLENDABLE,
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
        // The sky by the shell method seen from 2 m; the maps are uploaded once.
        let model =
            SkyModel::new(&Atmosphere::earth(), &SkySettings::default(), 2.0).expect("a model");
        let sky = GpuSkyModel::new(&gpu, model).expect("the sky on the GPU");
        // The sky's pass for this program's targets: the surface and its depth buffer.
        let target = SkyTarget {
            format: config.format,
            depth: Some(DepthTarget {
                format: DEPTH,
                reversed_z: false,
            }),
        };
        let mut sky_pass = SkyPass::new(&gpu, target).expect("the sky's pipeline");
        sky_pass.exposure = 0.05;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("ground"),
            source: wgpu::ShaderSource::Wgsl(GROUND.into()),
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
            size: 80,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let ground_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ground"),
            layout: &ground.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            }],
        });
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
        let eye = Vec3::new(0.0, 2.0, 0.0);
        let yaw = self.yaw_deg.to_radians() as f32;
        let forward = Vec3::new(yaw.sin(), 0.05, -yaw.cos()).normalize();
        let fov_deg = 60.0f32;
        let camera = Camera::look_at(eye, eye + forward, Vec3::Y, Fov::Vertical(fov_deg), size)
            .expect("a camera");
        let aspect = size.0 as f32 / size.1 as f32;
        let clip_from_world = Mat4::perspective_rh(fov_deg.to_radians(), aspect, 0.5, 50_000.0)
            * Mat4::look_to_rh(eye, forward, Vec3::Y);
        let sun = Sun::from_degrees(self.sun_elevation_deg, 180.0).expect("a sun");
        let to_sun = sun.toward();
        let mut uniforms = clip_from_world.to_cols_array().to_vec();
        uniforms.extend([to_sun.x, to_sun.y, to_sun.z, 0.0]);
        self.queue
            .write_buffer(&self.uniforms, 0, bytemuck::cast_slice(&uniforms));
        let mut encoder = self.device.create_command_encoder(&Default::default());
        // atmo records this sun's maps into the program's encoder...
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
}

fn main() {
    let event_loop = EventLoop::new().expect("a display (DISPLAY or WAYLAND_DISPLAY)");
    event_loop
        .run_app(&mut App::default())
        .expect("the event loop");
}
