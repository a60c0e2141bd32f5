//! Rendering without a window: a GPU of our own, images back on the CPU.
//! Used by `flexiso render` and the render tests; works on software
//! adapters (Mesa llvmpipe/lavapipe) as well as real GPUs.

use super::{Camera, ClipPlane, CutBox, RenderError, Renderer, SliceQuad};

/// A device of our own, for headless use.
pub struct Gpu {
    /// The adapter the device was made from.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
}

impl Gpu {
    /// Opens the default adapter with no display: backends from
    /// `WGPU_BACKEND` (e.g. `vulkan`, `gl`), software (CPU) adapters
    /// accepted, the adapter's own limits. [`RenderError::NoAdapter`] when
    /// there is none: install Mesa's `mesa-vulkan-drivers` on a machine
    /// without a GPU.
    pub fn new() -> Result<Gpu, RenderError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        }))
        .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("flexiso headless"),
            required_features: wgpu::Features::empty(),
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| RenderError::NoDevice(e.to_string()))?;
        Ok(Gpu {
            adapter,
            device,
            queue,
        })
    }

    /// A renderer on this device, with 4× MSAA when the adapter allows.
    pub fn renderer(&self) -> Renderer {
        Renderer::new(&self.device, Renderer::sample_count_for(&self.adapter))
    }

    /// A one-line description of the adapter (name and backend).
    pub fn describe(&self) -> String {
        let info = self.adapter.get_info();
        format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type)
    }
}

/// A mesh handed to [`render_to_image`].
#[derive(Clone, Copy, Debug)]
pub struct HeadlessMesh<'a> {
    /// Vertex positions.
    pub positions: &'a [[f32; 3]],
    /// One normal per position, or empty to compute them.
    pub normals: &'a [[f32; 3]],
    /// Three corners per triangle.
    pub indices: &'a [u32],
    /// sRGB colour with straight alpha (see [`Renderer::set_style`]).
    pub colour: [f32; 4],
}

/// Everything [`render_scene_to_image`] draws.
#[derive(Clone, Debug, Default)]
pub struct HeadlessScene<'a> {
    /// The meshes.
    pub meshes: Vec<HeadlessMesh<'a>>,
    /// The faint volume box.
    pub bounds: Option<([f32; 3], [f32; 3])>,
    /// None: the default view fitted to the bounds (or the meshes).
    pub camera: Option<Camera>,
    /// Slices, at most [`context::MAX_SLICES`](super::context::MAX_SLICES).
    pub slices: Vec<SliceQuad>,
    /// The clipping plane.
    pub clip: Option<ClipPlane>,
    /// The cut-away box.
    pub cut_box: Option<CutBox>,
    /// The model frame's placement in the world
    /// ([`Renderer::set_placement`]; None: the identity).
    pub placement: Option<glam::Mat4>,
}

/// Renders `meshes` into a `width × height` image on a GPU of its own.
/// `bounds` draws the faint volume box; `camera` None fits the default view
/// to the bounds (or to the meshes when there are none).
pub fn render_to_image(
    meshes: &[HeadlessMesh<'_>],
    bounds: Option<([f32; 3], [f32; 3])>,
    camera: Option<&Camera>,
    width: u32,
    height: u32,
) -> anyhow::Result<image::RgbaImage> {
    render_scene_to_image(
        &HeadlessScene {
            meshes: meshes.to_vec(),
            bounds,
            camera: camera.copied(),
            ..Default::default()
        },
        width,
        height,
    )
}

/// Renders `scene` into a `width × height` image on a GPU of its own.
pub fn render_scene_to_image(
    scene: &HeadlessScene<'_>,
    width: u32,
    height: u32,
) -> anyhow::Result<image::RgbaImage> {
    let gpu = Gpu::new()?;
    let mut renderer = gpu.renderer();
    for (i, m) in scene.meshes.iter().enumerate() {
        let id = i as u64;
        renderer.set_mesh(
            &gpu.device,
            &gpu.queue,
            id,
            m.positions,
            m.normals,
            m.indices,
        )?;
        renderer.set_style(id, m.colour, true, false);
    }
    for (i, q) in scene.slices.iter().enumerate() {
        renderer.set_slice(i, Some(q.clone()));
    }
    renderer.set_clip(scene.clip);
    renderer.set_cut_box(scene.cut_box);
    let placement = scene.placement.unwrap_or(glam::Mat4::IDENTITY);
    renderer.set_placement(placement);
    let bounds = scene.bounds;
    if let Some((lo, hi)) = bounds {
        renderer.set_bounds(lo, hi);
    }
    let camera = match scene.camera {
        Some(c) => c,
        None => {
            let mut c = Camera::default();
            let placed = bounds.map(|(lo, hi)| super::placed_box(placement, lo, hi));
            if let Some((lo, hi)) = placed.or_else(|| renderer.visible_bounds()) {
                c.fit(lo, hi);
            }
            c
        }
    };
    renderer.render(&gpu.device, &gpu.queue, &camera, width, height);
    Ok(renderer.read_image(&gpu.device, &gpu.queue)?)
}
