//! The offscreen mesh renderer (see the module doc of [`crate::render`]).

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

use super::camera::Camera;
use super::context::{ClipPlane, CutBox, MAX_SLICES, SliceQuad, SliceSlot, SliceVertex};
use super::geometry::{Corners, GpuVertex, PreparedMesh, ray_box};
use super::{MeshId, RenderError};

/// Format of the colour texture [`Renderer::render`] produces: plain
/// (not sRGB-aware) RGBA8 holding sRGB-encoded colour, which is what egui
/// expects of a native texture and what a PNG stores.
pub const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Format of the depth buffer.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Default colour of a mesh that has no style yet (sRGB, a light steel blue).
pub const DEFAULT_COLOUR: [f32; 4] = [0.69, 0.77, 0.87, 1.0];

/// Default background (sRGB, opaque dark grey, close to egui's dark panels).
pub const DEFAULT_BACKGROUND: [f32; 4] = [0.10, 0.10, 0.11, 1.0];

/// Colour of the bounding box lines (sRGB, straight alpha: faint grey).
const LINE_COLOUR: [f32; 4] = [0.75, 0.75, 0.78, 0.45];

/// Bytes per vertex on the GPU: quantised position and octahedral normal
/// ([`GpuVertex`]).
const VERTEX_BYTES: u64 = std::mem::size_of::<GpuVertex>() as u64;

/// How a mesh is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshStyle {
    /// sRGB colour in `[0, 1]` with straight alpha; alpha < 1 draws the mesh
    /// transparent (after the opaque ones, back to front), alpha 0 hides it.
    pub colour: [f32; 4],
    /// Hidden meshes are neither drawn nor picked.
    pub visible: bool,
    /// Drawn with a warm rim (the selection).
    pub highlighted: bool,
}

impl Default for MeshStyle {
    fn default() -> Self {
        MeshStyle {
            colour: DEFAULT_COLOUR,
            visible: true,
            highlighted: false,
        }
    }
}

/// Uniforms shared by every draw of a frame (layout matches `Frame` in
/// the shaders).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FrameUniform {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    fill_dir: [f32; 4],
    line_colour: [f32; 4],
    /// The clipping plane: normal (xyz) and offset (w).
    clip: [f32; 4],
    /// x: 1 when the clipping plane is on.
    clip_on: [f32; 4],
    /// The cut-away box's low corner (xyz); w: 1 when it is on.
    cut_lo: [f32; 4],
    /// Its high corner.
    cut_hi: [f32; 4],
    /// The placement: model frame to world ([`Renderer::set_placement`]).
    model: [[f32; 4]; 4],
    /// Its inverse transpose (upper 3×3), for normals.
    normal_model: [[f32; 4]; 4],
}

/// Per-mesh uniforms (layout matches `Style` in mesh.wgsl).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct StyleUniform {
    colour: [f32; 4],
    flags: [f32; 4],
    /// World position of quantised 0 (xyz).
    origin: [f32; 4],
    /// World units per quantisation step (xyz).
    scale: [f32; 4],
}

/// One mesh: the CPU copy for picking, its GPU buffers and style.
struct Mesh {
    /// What the buffers hold.
    cpu: Arc<PreparedMesh>,
    vertex_buffer: Option<wgpu::Buffer>,
    index_buffer: Option<wgpu::Buffer>,
    index_count: u32,
    /// Newer geometry on its way to the GPU.
    pending: Option<PendingUpload>,
    /// The buffers of the geometry drawn before the current one, kept for
    /// the next upload that spans frames: writing into memory already
    /// touched costs no page faults (a drag replaces the same mesh again
    /// and again).
    spare: Option<(wgpu::Buffer, wgpu::Buffer)>,
    style: MeshStyle,
    style_buffer: wgpu::Buffer,
    style_bind: wgpu::BindGroup,
    style_dirty: bool,
}

impl Mesh {
    fn drawn(&self) -> bool {
        self.style.visible && self.style.colour[3] > 0.0 && self.index_count > 0
    }
}

/// A mesh being copied to the GPU, possibly over several frames.
struct PendingUpload {
    mesh: Arc<PreparedMesh>,
    /// Fresh vertex and index buffers, once a partial copy has begun.
    buffers: Option<(wgpu::Buffer, wgpu::Buffer)>,
    /// Bytes copied so far: the vertices, then the indices.
    written: u64,
}

/// The render targets, recreated when the size changes.
struct Target {
    size: (u32, u32),
    /// Multisampled colour, when MSAA is on.
    msaa: Option<wgpu::TextureView>,
    /// The single-sampled result (resolve target with MSAA).
    colour: wgpu::Texture,
    colour_view: wgpu::TextureView,
    depth: wgpu::TextureView,
}

/// The bounding box lines.
struct BoundsLines {
    min: [f32; 3],
    max: [f32; 3],
    buffers: Option<(wgpu::Buffer, wgpu::Buffer)>,
}

/// Draws a set of lit meshes into its own offscreen colour and depth
/// textures. See the [module doc](crate::render) for how to use it.
pub struct Renderer {
    sample_count: u32,
    style_layout: wgpu::BindGroupLayout,
    opaque: wgpu::RenderPipeline,
    /// Transparent meshes, drawn twice: triangles facing away on screen
    /// (cull front), then those facing the viewer (cull back).
    transparent_back: wgpu::RenderPipeline,
    transparent_front: wgpu::RenderPipeline,
    lines: wgpu::RenderPipeline,
    /// Textured quads (slices), opaque and unlit.
    slice_pipeline: wgpu::RenderPipeline,
    slice_layout: wgpu::BindGroupLayout,
    slice_sampler: wgpu::Sampler,
    slices: [SliceSlot; MAX_SLICES],
    clip: Option<ClipPlane>,
    cut_box: Option<CutBox>,
    /// Model frame to world (see [`Renderer::set_placement`]).
    placement: Mat4,
    frame_buffer: wgpu::Buffer,
    frame_bind: wgpu::BindGroup,
    meshes: BTreeMap<MeshId, Mesh>,
    bounds: Option<BoundsLines>,
    target: Option<Target>,
    generation: u64,
    /// Bumped by every change to what is drawn.
    scene_version: u64,
    /// What the last render showed: camera, size, scene version.
    last_render: Option<(Camera, (u32, u32), u64)>,
    background: [f32; 4],
}

impl Renderer {
    /// The MSAA sample count to pass to [`Renderer::new`] for this adapter:
    /// 4 when the adapter can multisample and resolve both [`COLOUR_FORMAT`]
    /// and [`DEPTH_FORMAT`] 4×, else 1.
    pub fn sample_count_for(adapter: &wgpu::Adapter) -> u32 {
        use wgpu::TextureFormatFeatureFlags as F;
        let colour = adapter.get_texture_format_features(COLOUR_FORMAT).flags;
        let depth = adapter.get_texture_format_features(DEPTH_FORMAT).flags;
        if colour.sample_count_supported(4)
            && colour.contains(F::MULTISAMPLE_RESOLVE)
            && depth.sample_count_supported(4)
        {
            4
        } else {
            1
        }
    }

    /// Creates the pipelines. `sample_count` is 1 or 4 (anything else is
    /// taken as 1); get it from [`Renderer::sample_count_for`].
    pub fn new(device: &wgpu::Device, sample_count: u32) -> Self {
        let sample_count = if sample_count == 4 { 4 } else { 1 };
        let uniform_entry = |visibility| wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("flexiso frame"),
            entries: &[uniform_entry(wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let style_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("flexiso mesh style"),
            entries: &[uniform_entry(wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let frame_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("flexiso frame"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("flexiso frame"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buffer.as_entire_binding(),
            }],
        });

        let mesh_shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("flexiso mesh.wgsl"),
            source: wgpu::ShaderSource::Wgsl(
                concat!(
                    include_str!("../../shaders/frame.wgsl"),
                    include_str!("../../shaders/mesh.wgsl")
                )
                .into(),
            ),
        });
        let lines_shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("flexiso lines.wgsl"),
            source: wgpu::ShaderSource::Wgsl(
                concat!(
                    include_str!("../../shaders/frame.wgsl"),
                    include_str!("../../shaders/lines.wgsl")
                )
                .into(),
            ),
        });
        let mesh_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("flexiso mesh"),
            bind_group_layouts: &[Some(&frame_layout), Some(&style_layout)],
            immediate_size: 0,
        });
        let lines_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("flexiso lines"),
            bind_group_layouts: &[Some(&frame_layout)],
            immediate_size: 0,
        });

        let mesh_attributes = wgpu::vertex_attr_array![0 => Unorm16x4, 1 => Snorm16x2];
        let line_attributes = wgpu::vertex_attr_array![0 => Float32x3];
        // Straight-alpha "over" for colour; alpha accumulates so an opaque
        // background stays opaque (egui composites the texture as is).
        let blend = wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::SrcAlpha,
                dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent::OVER,
        };
        let multisample = wgpu::MultisampleState {
            count: sample_count,
            mask: !0,
            alpha_to_coverage_enabled: false,
        };
        let mesh_pipeline = |label,
                             depth_write: bool,
                             blend: Option<wgpu::BlendState>,
                             cull_mode: Option<wgpu::Face>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&mesh_layout),
                vertex: wgpu::VertexState {
                    module: &mesh_shader,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: VERTEX_BYTES,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &mesh_attributes,
                    })],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(depth_write),
                    depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample,
                fragment: Some(wgpu::FragmentState {
                    module: &mesh_shader,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: COLOUR_FORMAT,
                        blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        // Opaque: no culling, contours are open or closed and seen from
        // both sides.
        let opaque = mesh_pipeline("flexiso opaque meshes", true, None, None);
        // Transparent meshes test depth against the opaque ones but do not
        // write it, so all transparent layers blend.
        let transparent_back = mesh_pipeline(
            "flexiso transparent meshes, far side",
            false,
            Some(blend),
            Some(wgpu::Face::Front),
        );
        let transparent_front = mesh_pipeline(
            "flexiso transparent meshes, near side",
            false,
            Some(blend),
            Some(wgpu::Face::Back),
        );
        let lines = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("flexiso bounds"),
            layout: Some(&lines_layout),
            vertex: wgpu::VertexState {
                module: &lines_shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 12,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &line_attributes,
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::LineList,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample,
            fragment: Some(wgpu::FragmentState {
                module: &lines_shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: COLOUR_FORMAT,
                    blend: Some(blend),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });

        let slice_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("flexiso slice"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let slice_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("flexiso slice"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let slice_shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("flexiso slice.wgsl"),
            source: wgpu::ShaderSource::Wgsl(
                concat!(
                    include_str!("../../shaders/frame.wgsl"),
                    include_str!("../../shaders/slice.wgsl")
                )
                .into(),
            ),
        });
        let slice_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("flexiso slice"),
                bind_group_layouts: &[Some(&frame_layout), Some(&slice_layout)],
                immediate_size: 0,
            });
        let slice_attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x2];
        let slice_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("flexiso slices"),
            layout: Some(&slice_pipeline_layout),
            vertex: wgpu::VertexState {
                module: &slice_shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<SliceVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &slice_attributes,
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample,
            fragment: Some(wgpu::FragmentState {
                module: &slice_shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: COLOUR_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });

        Renderer {
            sample_count,
            style_layout,
            opaque,
            transparent_back,
            transparent_front,
            lines,
            slice_pipeline,
            slice_layout,
            slice_sampler,
            slices: Default::default(),
            clip: None,
            cut_box: None,
            placement: Mat4::IDENTITY,
            frame_buffer,
            frame_bind,
            meshes: BTreeMap::new(),
            bounds: None,
            target: None,
            generation: 0,
            scene_version: 0,
            last_render: None,
            background: DEFAULT_BACKGROUND,
        }
    }

    /// The MSAA sample count in use (1 or 4).
    pub fn sample_count(&self) -> u32 {
        self.sample_count
    }

    /// Adds or replaces mesh `id` and uploads it at once. `normals` has one
    /// normal per position, or is empty to have them computed from the
    /// triangles ([`compute_normals`](super::compute_normals)); `indices`
    /// holds three corners per triangle. A replaced mesh keeps its style;
    /// buffers are reused when the new data fits. An empty mesh is kept
    /// (and draws nothing). Errors leave the previous mesh in place. Also
    /// finishes every upload still pending.
    pub fn set_mesh(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        id: impl Into<MeshId>,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        indices: &[u32],
    ) -> Result<(), RenderError> {
        let id = id.into();
        let mesh = PreparedMesh::new(positions, normals, indices)
            .map_err(|reason| RenderError::InvalidMesh { id, reason })?;
        self.set_prepared_mesh(device, id, Arc::new(mesh))?;
        self.upload_pending(device, queue, u64::MAX);
        Ok(())
    }

    /// Adds or replaces mesh `id` with a mesh prepared elsewhere (another
    /// thread), to be copied to the GPU by [`Renderer::upload_pending`]:
    /// until then the previous geometry, if any, is drawn. A replaced mesh
    /// keeps its style. Errors (beyond the device's buffer limit) leave the
    /// previous mesh in place.
    pub fn set_prepared_mesh(
        &mut self,
        device: &wgpu::Device,
        id: impl Into<MeshId>,
        mesh: Arc<PreparedMesh>,
    ) -> Result<(), RenderError> {
        let id = id.into();
        let max = device.limits().max_buffer_size;
        let vertex_bytes = mesh.vertices.len() as u64 * VERTEX_BYTES;
        let index_bytes = mesh.indices.bytes().len() as u64;
        if vertex_bytes > max || index_bytes > max {
            return Err(RenderError::InvalidMesh {
                id,
                reason: format!(
                    "{} vertices and {} triangles exceed the device's buffer limit of {max} bytes",
                    mesh.vertices.len(),
                    mesh.num_triangles()
                ),
            });
        }
        if !self.meshes.contains_key(&id) {
            let (style_buffer, style_bind) = self.style_resources(device);
            self.meshes.insert(
                id,
                Mesh {
                    cpu: Arc::default(),
                    vertex_buffer: None,
                    index_buffer: None,
                    index_count: 0,
                    pending: None,
                    spare: None,
                    style: MeshStyle::default(),
                    style_buffer,
                    style_bind,
                    style_dirty: true,
                },
            );
        }
        if let Some(entry) = self.meshes.get_mut(&id) {
            entry.pending = Some(PendingUpload {
                mesh,
                buffers: None,
                written: 0,
            });
        }
        Ok(())
    }

    /// Copies at most `budget` bytes of the pending meshes to the GPU, in
    /// id order; true while some remain. A mesh that fits in what is left
    /// of the budget goes in whole (into its old buffers when they are big
    /// enough); a larger one is copied into fresh buffers over several
    /// calls and replaces the old geometry when complete. So a frame can
    /// bound its upload time however big the meshes are.
    pub fn upload_pending(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        budget: u64,
    ) -> bool {
        // Write offsets and sizes stay multiples of COPY_BUFFER_ALIGNMENT.
        let mut budget = budget - budget % wgpu::COPY_BUFFER_ALIGNMENT;
        let mut changed = false;
        let mut left = false;
        for entry in self.meshes.values_mut() {
            let Some(pending) = &mut entry.pending else {
                continue;
            };
            let mesh = Arc::clone(&pending.mesh);
            let vertices: &[u8] = bytemuck::cast_slice(&mesh.vertices);
            let indices: &[u8] = mesh.indices.bytes();
            let total = (vertices.len() + indices.len()) as u64;
            let (vb, ib) = if mesh.indices.is_empty() {
                (None, None)
            } else if pending.written == 0 && total <= budget {
                budget -= total;
                (
                    Some(upload(
                        device,
                        queue,
                        entry.vertex_buffer.take(),
                        vertices,
                        wgpu::BufferUsages::VERTEX,
                        "flexiso mesh vertices",
                    )),
                    Some(upload(
                        device,
                        queue,
                        entry.index_buffer.take(),
                        indices,
                        wgpu::BufferUsages::INDEX,
                        "flexiso mesh indices",
                    )),
                )
            } else {
                if budget == 0 {
                    left = true;
                    continue;
                }
                let spare = &mut entry.spare;
                let (vb, ib) = pending.buffers.get_or_insert_with(|| {
                    let fits = |(vb, ib): &(wgpu::Buffer, wgpu::Buffer)| {
                        vb.size() >= vertices.len() as u64 && ib.size() >= indices.len() as u64
                    };
                    spare.take().filter(fits).unwrap_or_else(|| {
                        (
                            new_buffer(
                                device,
                                vertices.len() as u64,
                                wgpu::BufferUsages::VERTEX,
                                "flexiso mesh vertices",
                            ),
                            new_buffer(
                                device,
                                indices.len() as u64,
                                wgpu::BufferUsages::INDEX,
                                "flexiso mesh indices",
                            ),
                        )
                    })
                });
                // Vertices first, then indices, in chunks of what the
                // budget allows.
                for (buffer, bytes, start) in [
                    (&*vb, vertices, 0u64),
                    (&*ib, indices, vertices.len() as u64),
                ] {
                    let end = start + bytes.len() as u64;
                    if pending.written >= end || budget == 0 {
                        continue;
                    }
                    let from = pending.written - start;
                    let n = (end - pending.written).min(budget);
                    queue.write_buffer(buffer, from, &bytes[from as usize..(from + n) as usize]);
                    pending.written += n;
                    budget -= n;
                }
                if pending.written < total {
                    left = true;
                    continue;
                }
                let (vb, ib) = pending.buffers.take().expect("buffers were created above");
                if let (Some(old_vb), Some(old_ib)) =
                    (entry.vertex_buffer.take(), entry.index_buffer.take())
                {
                    entry.spare = Some((old_vb, old_ib));
                }
                (Some(vb), Some(ib))
            };
            entry.vertex_buffer = vb;
            entry.index_buffer = ib;
            // The quantisation box is the new geometry's.
            entry.style_dirty = true;
            entry.index_count = mesh.indices.len() as u32;
            entry.cpu = mesh;
            entry.pending = None;
            changed = true;
        }
        if changed {
            self.scene_version += 1;
        }
        left
    }

    /// Whether some mesh waits for [`Renderer::upload_pending`].
    pub fn has_pending_uploads(&self) -> bool {
        self.meshes.values().any(|m| m.pending.is_some())
    }

    fn style_resources(&self, device: &wgpu::Device) -> (wgpu::Buffer, wgpu::BindGroup) {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("flexiso mesh style"),
            size: std::mem::size_of::<StyleUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("flexiso mesh style"),
            layout: &self.style_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: buffer.as_entire_binding(),
            }],
        });
        (buffer, bind)
    }

    /// Removes mesh `id` (and its GPU buffers); false if there was none.
    pub fn remove_mesh(&mut self, id: impl Into<MeshId>) -> bool {
        self.scene_version += 1;
        self.meshes.remove(&id.into()).is_some()
    }

    /// Removes every mesh.
    pub fn clear_meshes(&mut self) {
        self.scene_version += 1;
        self.meshes.clear();
    }

    /// The ids of the meshes held, ascending.
    pub fn mesh_ids(&self) -> Vec<MeshId> {
        self.meshes.keys().copied().collect()
    }

    /// Whether mesh `id` is held.
    pub fn has_mesh(&self, id: impl Into<MeshId>) -> bool {
        self.meshes.contains_key(&id.into())
    }

    /// Sets how mesh `id` is drawn: `colour` is sRGB in `[0, 1]` with
    /// straight alpha (alpha < 1: transparent). Only a uniform is rewritten
    /// at the next render; the geometry is not touched. False (and no
    /// effect) if there is no such mesh: set the mesh first.
    pub fn set_style(
        &mut self,
        id: impl Into<MeshId>,
        colour: [f32; 4],
        visible: bool,
        highlighted: bool,
    ) -> bool {
        let Some(mesh) = self.meshes.get_mut(&id.into()) else {
            return false;
        };
        let style = MeshStyle {
            colour: colour.map(|c| {
                if c.is_finite() {
                    c.clamp(0.0, 1.0)
                } else {
                    0.0
                }
            }),
            visible,
            highlighted,
        };
        if mesh.style != style {
            mesh.style = style;
            mesh.style_dirty = true;
            self.scene_version += 1;
        }
        true
    }

    /// The style of mesh `id`.
    pub fn style(&self, id: impl Into<MeshId>) -> Option<MeshStyle> {
        self.meshes.get(&id.into()).map(|m| m.style)
    }

    /// The world box around the visible meshes `(min, max)`, or None when
    /// nothing is drawn (for [`Camera::fit`]): their model boxes placed
    /// in the world ([`placed_box`]).
    pub fn visible_bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for m in self.meshes.values().filter(|m| m.drawn()) {
            lo = lo.min(m.cpu.bbox.0);
            hi = hi.max(m.cpu.bbox.1);
        }
        lo.cmple(hi)
            .all()
            .then(|| placed_box(self.placement, lo.to_array(), hi.to_array()))
    }

    /// Places the model frame in the world: every mesh, the bounding box,
    /// the slices and the clipping plane are given in the model frame
    /// (for a volume: its grid, index × spacing), and `model` (an
    /// invertible affine map) moves them where the camera looks, e.g. a
    /// scanner's patient coordinates. So the volume's box becomes a
    /// parallelepiped when the volume's axes are sheared or rotated, and
    /// the clip and the slices stay along the volume's axes. Picking
    /// returns world points. Identity by default; a map that is not
    /// invertible (or not finite) is refused and the old one kept (false).
    pub fn set_placement(&mut self, model: Mat4) -> bool {
        let det = model.determinant();
        if !(det.is_finite() && det.abs() > f32::EPSILON && model.is_finite()) {
            return false;
        }
        if self.placement != model {
            self.placement = model;
            self.scene_version += 1;
        }
        true
    }

    /// The placement in use ([`Renderer::set_placement`]).
    pub fn placement(&self) -> Mat4 {
        self.placement
    }

    /// Draws the faint box `[min, max]` (the volume's extent).
    pub fn set_bounds(&mut self, min: [f32; 3], max: [f32; 3]) {
        if let Some(b) = &self.bounds
            && b.min == min
            && b.max == max
        {
            return;
        }
        self.scene_version += 1;
        self.bounds = Some(BoundsLines {
            min,
            max,
            buffers: None,
        });
    }

    /// Stops drawing the bounding box.
    pub fn clear_bounds(&mut self) {
        self.scene_version += 1;
        self.bounds = None;
    }

    /// Sets the background (sRGB, `[0, 1]`; alpha is written as given, keep
    /// it 1 for egui).
    pub fn set_background(&mut self, colour: [f32; 4]) {
        if self.background != colour {
            self.background = colour;
            self.scene_version += 1;
        }
    }

    /// Cuts every mesh with `clip` (None: no cut). Picking follows.
    pub fn set_clip(&mut self, clip: Option<ClipPlane>) {
        if self.clip != clip {
            self.clip = clip;
            self.scene_version += 1;
        }
    }

    /// The clipping plane in use.
    pub fn clip(&self) -> Option<ClipPlane> {
        self.clip
    }

    /// Cuts away what lies inside `cut` from every mesh (None: nothing).
    /// Picking follows.
    pub fn set_cut_box(&mut self, cut: Option<CutBox>) {
        if self.cut_box != cut {
            self.cut_box = cut;
            self.scene_version += 1;
        }
    }

    /// The cut-away box in use.
    pub fn cut_box(&self) -> Option<CutBox> {
        self.cut_box
    }

    /// Shows `quad` in slot `slot` (`0..MAX_SLICES`; others are ignored),
    /// or nothing there with None. The image is uploaded at the next
    /// render (into the old texture when it has the same size): call this
    /// only when the slice changed.
    pub fn set_slice(&mut self, slot: usize, quad: Option<SliceQuad>) {
        if let Some(s) = self.slices.get_mut(slot) {
            s.quad = quad;
            s.dirty = true;
            self.scene_version += 1;
        }
    }

    /// The quad in slot `slot`, if any.
    pub fn slice(&self, slot: usize) -> Option<&SliceQuad> {
        self.slices.get(slot).and_then(|s| s.quad.as_ref())
    }

    /// Renders the scene from `camera` into the renderer's own
    /// `width × height` textures (recreated when the size changes; sizes are
    /// clamped to `1..=max_texture_dimension_2d`) and submits the work to
    /// `queue`. Returns the single-sampled colour texture ([`COLOUR_FORMAT`]);
    /// [`Renderer::colour_view`] is its view.
    pub fn render(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> &wgpu::Texture {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("flexiso render"),
        });
        self.render_with_encoder(device, queue, &mut encoder, camera, width, height);
        queue.submit([encoder.finish()]);
        &self.ensure_target(device, width, height).colour
    }

    /// Like [`Renderer::render`] but records into `encoder` instead of
    /// submitting (for egui_wgpu's `CallbackTrait::prepare`). Uniform and
    /// buffer updates go through `queue.write_buffer`, which wgpu orders
    /// before the next submission.
    pub fn render_with_encoder(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
        width: u32,
        height: u32,
    ) {
        self.ensure_target(device, width, height);
        let Some(target) = &self.target else {
            return;
        };
        let (w, h) = target.size;
        self.last_render = Some((*camera, (w, h), self.scene_version));
        let aspect = w as f32 / h as f32;
        let eye = camera.eye();
        // The fill light comes from above-left-behind the viewer, in world
        // coordinates derived from the view so it turns with the camera.
        let view_inv = camera.view().inverse();
        let fill = view_inv
            .transform_vector3(Vec3::new(-0.6, 0.7, 0.4))
            .normalize_or(Vec3::Z);
        let frame = FrameUniform {
            view_proj: camera.view_proj(aspect).to_cols_array_2d(),
            eye: eye.extend(1.0).to_array(),
            fill_dir: fill.extend(0.0).to_array(),
            line_colour: LINE_COLOUR,
            clip: self.clip.map_or([0.0; 4], |c| c.as_vec4()),
            clip_on: [f32::from(u8::from(self.clip.is_some())), 0.0, 0.0, 0.0],
            cut_lo: self
                .cut_box
                .map_or([0.0; 4], |b| [b.lo[0], b.lo[1], b.lo[2], 1.0]),
            cut_hi: self
                .cut_box
                .map_or([0.0; 4], |b| [b.hi[0], b.hi[1], b.hi[2], 0.0]),
            model: self.placement.to_cols_array_2d(),
            normal_model: Mat4::from_mat3(
                glam::Mat3::from_mat4(self.placement).inverse().transpose(),
            )
            .to_cols_array_2d(),
        };
        queue.write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&frame));

        for mesh in self.meshes.values_mut().filter(|m| m.style_dirty) {
            let c = mesh.style.colour;
            let (origin, scale) = mesh.cpu.dequantise();
            let uniform = StyleUniform {
                colour: [
                    linear_from_srgb(c[0]),
                    linear_from_srgb(c[1]),
                    linear_from_srgb(c[2]),
                    c[3],
                ],
                flags: [f32::from(u8::from(mesh.style.highlighted)), 0.0, 0.0, 0.0],
                origin: origin.extend(0.0).to_array(),
                scale: scale.extend(0.0).to_array(),
            };
            queue.write_buffer(&mesh.style_buffer, 0, bytemuck::bytes_of(&uniform));
            mesh.style_dirty = false;
        }
        for s in &mut self.slices {
            s.upload(device, queue, &self.slice_layout, &self.slice_sampler);
        }
        if let Some(b) = &mut self.bounds
            && b.buffers.is_none()
        {
            b.buffers = Some(box_lines(device, b.min, b.max));
        }

        // Opaque first (any order: depth sorts them), then the transparent
        // ones back to front by the distance of their box centre from the
        // eye. Ties are broken by id so the order is deterministic.
        let mut opaque = Vec::new();
        let mut transparent = Vec::new();
        for (&id, m) in self.meshes.iter().filter(|(_, m)| m.drawn()) {
            if m.style.colour[3] >= 1.0 {
                opaque.push(m);
            } else {
                let centre = self.placement.transform_point3(m.cpu.centre());
                transparent.push((centre.distance_squared(eye), id, m));
            }
        }
        transparent.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));

        let (view, resolve) = match &target.msaa {
            Some(msaa) => (msaa, Some(&target.colour_view)),
            None => (&target.colour_view, None),
        };
        let bg = self.background.map(f64::from);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("flexiso scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: resolve,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: bg[0],
                        g: bg[1],
                        b: bg[2],
                        a: bg[3],
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &target.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0), // reversed depth: 0 is far
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &self.frame_bind, &[]);
        let draw = |pass: &mut wgpu::RenderPass<'_>, m: &Mesh| {
            if let (Some(vb), Some(ib)) = (&m.vertex_buffer, &m.index_buffer) {
                pass.set_bind_group(1, &m.style_bind, &[]);
                pass.set_vertex_buffer(0, vb.slice(..));
                match &m.cpu.indices {
                    Corners::Short { runs, .. } => {
                        pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint16);
                        for r in runs {
                            pass.draw_indexed(r.start..r.end, r.base as i32, 0..1);
                        }
                    }
                    Corners::Long(_) => {
                        pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
                        pass.draw_indexed(0..m.index_count, 0, 0..1);
                    }
                }
            }
        };
        pass.set_pipeline(&self.opaque);
        for m in opaque {
            draw(&mut pass, m);
        }
        pass.set_pipeline(&self.slice_pipeline);
        for s in &self.slices {
            if let (Some(g), Some(_)) = (&s.gpu, &s.quad) {
                pass.set_bind_group(1, &g.bind, &[]);
                pass.set_vertex_buffer(0, g.vertices.slice(..));
                pass.draw(0..6, 0..1);
            }
        }
        if let Some(BoundsLines {
            buffers: Some((vb, ib)),
            ..
        }) = &self.bounds
        {
            pass.set_pipeline(&self.lines);
            pass.set_vertex_buffer(0, vb.slice(..));
            pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..24, 0, 0..1);
        }
        // Within a closed mesh, its far half is drawn before its near half:
        // with counter-clockwise-outward winding (`ccw_outward`) the far half
        // is what faces away on screen, otherwise the reverse.
        for (_, _, m) in transparent {
            let (first, second) = if m.cpu.ccw_outward {
                (&self.transparent_back, &self.transparent_front)
            } else {
                (&self.transparent_front, &self.transparent_back)
            };
            pass.set_pipeline(first);
            draw(&mut pass, m);
            pass.set_pipeline(second);
            draw(&mut pass, m);
        }
    }

    /// Creates the targets when missing or of another size.
    fn ensure_target(&mut self, device: &wgpu::Device, width: u32, height: u32) -> &Target {
        let max = device.limits().max_texture_dimension_2d.max(1);
        let size = (width.clamp(1, max), height.clamp(1, max));
        if self.target.as_ref().is_none_or(|t| t.size != size) {
            self.target = Some(create_target(device, size, self.sample_count));
            self.generation += 1;
        }
        match &self.target {
            Some(t) => t,
            None => unreachable!("the target was just created"),
        }
    }

    /// Whether the texture already shows this camera at this size with
    /// nothing changed since: the app may then skip [`Renderer::render`]
    /// (software rendering makes every skipped frame count).
    pub fn is_current(&self, camera: &Camera, width: u32, height: u32) -> bool {
        self.last_render.is_some_and(|(c, size, version)| {
            c == *camera
                && version == self.scene_version
                && self
                    .target
                    .as_ref()
                    .is_some_and(|t| t.size == size && size == (width.max(1), height.max(1)))
        })
    }

    /// The colour texture of the last render, if any.
    pub fn colour_texture(&self) -> Option<&wgpu::Texture> {
        self.target.as_ref().map(|t| &t.colour)
    }

    /// A view of the colour texture of the last render, if any: register it
    /// with egui_wgpu (see [`EguiTexture`](super::EguiTexture)).
    pub fn colour_view(&self) -> Option<&wgpu::TextureView> {
        self.target.as_ref().map(|t| &t.colour_view)
    }

    /// Counts target (re)creations: when it changes, the texture behind
    /// [`Renderer::colour_view`] is a new one and must be re-registered with
    /// egui.
    pub fn target_generation(&self) -> u64 {
        self.generation
    }

    /// The size of the current targets, if any.
    pub fn target_size(&self) -> Option<(u32, u32)> {
        self.target.as_ref().map(|t| t.size)
    }

    /// Copies the last render back to the CPU (blocks until the GPU is
    /// done). For screenshots and tests.
    pub fn read_image(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<image::RgbaImage, RenderError> {
        let target = self.target.as_ref().ok_or(RenderError::NothingRendered)?;
        read_texture(device, queue, &target.colour, target.size)
    }

    /// The nearest visible mesh under pixel `(x, y)` of a `width × height`
    /// viewport (origin top-left, any unit as long as all four agree) seen
    /// from `camera`: its id and the world position hit. Casts a ray on the
    /// CPU against the stored triangles, skipping meshes whose bounding box
    /// the ray misses or enters beyond the nearest hit so far. Hidden
    /// meshes, what the clipping plane and the cut-away box cut away and
    /// what lies behind a slice are not hit. The ray is cast in the model frame (the
    /// placement's inverse applied to the eye and the direction, so its
    /// parameter is the same in both) and the hit placed in the world.
    pub fn pick(
        &self,
        camera: &Camera,
        width: f32,
        height: f32,
        x: f32,
        y: f32,
    ) -> Option<(MeshId, [f32; 3])> {
        if !(width > 0.0 && height > 0.0 && x.is_finite() && y.is_finite()) {
            return None;
        }
        let ndc = [2.0 * x / width - 1.0, 1.0 - 2.0 * y / height];
        let (eye, dir) = camera.ray(ndc, width / height);
        let to_model = self.placement.inverse();
        let (eye, dir) = (
            to_model.transform_point3(eye),
            to_model.transform_vector3(dir),
        );
        // Only the part of the ray on the clip's kept side, in front of
        // the nearest slice, can hit: cast from where that part begins.
        let (t0, mut t1) = match &self.clip {
            Some(c) => c.kept_interval(eye, dir)?,
            None => (0.0, f32::INFINITY),
        };
        for s in self.slices.iter().filter_map(|s| s.quad.as_ref()) {
            if let Some(t) = s.ray_hit(eye, dir) {
                t1 = t1.min(t);
            }
        }
        if t1 <= t0 {
            return None;
        }
        // Outside the cut-away box: at most two intervals, nearest first;
        // the nearest kept hit is the first interval's nearest hit in it.
        let parts = match &self.cut_box {
            Some(b) => b.kept_parts(eye, dir, t0, t1),
            None => vec![(t0, t1)],
        };
        parts
            .into_iter()
            .find_map(|(a, b)| self.cast(eye + a * dir, dir, b - a))
    }

    /// The nearest drawn mesh hit by the ray `origin + t dir` for
    /// `0 <= t <= t1`.
    fn cast(&self, origin: Vec3, dir: Vec3, t1: f32) -> Option<(MeshId, [f32; 3])> {
        if t1 <= 0.0 {
            return None;
        }
        let mut candidates: Vec<(f32, MeshId, &Mesh)> = self
            .meshes
            .iter()
            .filter(|(_, m)| m.drawn())
            .filter_map(|(&id, m)| {
                ray_box(origin, dir, m.cpu.bbox.0, m.cpu.bbox.1).map(|t| (t, id, m))
            })
            .collect();
        candidates.retain(|c| c.0 <= t1);
        candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut best: Option<(f32, MeshId, Vec3)> = None;
        for (enter, id, m) in candidates {
            if best.is_some_and(|(t, _, _)| enter > t) {
                break;
            }
            if let Some((t, p)) = m.cpu.ray_hit(origin, dir)
                && best.is_none_or(|(bt, _, _)| t < bt)
            {
                best = Some((t, id, p));
            }
        }
        best.filter(|(t, _, _)| *t <= t1)
            .map(|(_, id, p)| (id, self.placement.transform_point3(p).to_array()))
    }

    /// The world-to-clip matrix the last render used for a `width × height`
    /// viewport (to project world points to the screen, e.g. labels;
    /// a point of the model frame is placed first, see
    /// [`Renderer::set_placement`]).
    pub fn view_proj(camera: &Camera, width: f32, height: f32) -> Mat4 {
        camera.view_proj(if height > 0.0 { width / height } else { 1.0 })
    }
}

/// The world box `(min, max)` around the box `[lo, hi]` of the model
/// frame placed by `model`: the bounds of its eight corners (the box
/// itself for a placement that only moves, scales or turns by right
/// angles; around a parallelepiped otherwise).
pub fn placed_box(model: Mat4, lo: [f32; 3], hi: [f32; 3]) -> ([f32; 3], [f32; 3]) {
    let mut a = Vec3::splat(f32::INFINITY);
    let mut b = Vec3::splat(f32::NEG_INFINITY);
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        );
        let w = model.transform_point3(c);
        a = a.min(w);
        b = b.max(w);
    }
    (a.to_array(), b.to_array())
}

/// Writes `data` into `old` when it is big enough, else into a new buffer
/// (with 25% headroom so a growing mesh is not reallocated every time).
fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    old: Option<wgpu::Buffer>,
    data: &[u8],
    usage: wgpu::BufferUsages,
    label: &str,
) -> wgpu::Buffer {
    if let Some(b) = old
        && b.size() >= data.len() as u64
    {
        queue.write_buffer(&b, 0, data);
        return b;
    }
    let buffer = new_buffer(
        device,
        data.len() as u64 + data.len() as u64 / 4,
        usage,
        label,
    );
    queue.write_buffer(&buffer, 0, data);
    buffer
}

/// A buffer of at least `len` bytes (capped at the device's limit, and a
/// multiple of COPY_BUFFER_ALIGNMENT) that can be written to.
fn new_buffer(
    device: &wgpu::Device,
    len: u64,
    usage: wgpu::BufferUsages,
    label: &str,
) -> wgpu::Buffer {
    let size = len
        .min(device.limits().max_buffer_size)
        .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
        .max(wgpu::COPY_BUFFER_ALIGNMENT);
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The 8 corners and 12 edges of a box.
fn box_lines(device: &wgpu::Device, lo: [f32; 3], hi: [f32; 3]) -> (wgpu::Buffer, wgpu::Buffer) {
    let corners: Vec<[f32; 3]> = (0..8)
        .map(|i| {
            [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ]
        })
        .collect();
    // Each edge joins corners differing in one bit.
    let mut edges: Vec<u32> = Vec::with_capacity(24);
    for i in 0u32..8 {
        for bit in [1, 2, 4] {
            if i & bit == 0 {
                edges.extend([i, i | bit]);
            }
        }
    }
    let vb = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("flexiso bounds vertices"),
        contents: bytemuck::cast_slice(&corners),
        usage: wgpu::BufferUsages::VERTEX,
    });
    let ib = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("flexiso bounds indices"),
        contents: bytemuck::cast_slice(&edges),
        usage: wgpu::BufferUsages::INDEX,
    });
    (vb, ib)
}

fn create_target(device: &wgpu::Device, size: (u32, u32), sample_count: u32) -> Target {
    let extent = wgpu::Extent3d {
        width: size.0,
        height: size.1,
        depth_or_array_layers: 1,
    };
    let texture = |label, format, samples, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: extent,
            mip_level_count: 1,
            sample_count: samples,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let colour = texture(
        "flexiso colour",
        COLOUR_FORMAT,
        1,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
    );
    let msaa = (sample_count > 1).then(|| {
        texture(
            "flexiso colour msaa",
            COLOUR_FORMAT,
            sample_count,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        )
        .create_view(&Default::default())
    });
    let depth = texture(
        "flexiso depth",
        DEPTH_FORMAT,
        sample_count,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    )
    .create_view(&Default::default());
    let colour_view = colour.create_view(&Default::default());
    Target {
        size,
        msaa,
        colour,
        colour_view,
        depth,
    }
}

/// Copies an RGBA8 texture into an image: rows are padded to 256 bytes in
/// the staging buffer (`COPY_BYTES_PER_ROW_ALIGNMENT`) and unpadded here.
fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    (width, height): (u32, u32),
) -> Result<image::RgbaImage, RenderError> {
    let row = width as u64 * 4;
    let padded = row.next_multiple_of(u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT));
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("flexiso readback"),
        size: padded * u64::from(height),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("flexiso readback"),
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
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
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    rx.recv()
        .map_err(|e| RenderError::Readback(e.to_string()))?
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    let mut pixels = Vec::with_capacity((row * u64::from(height)) as usize);
    {
        let mapped = buffer
            .get_mapped_range(..)
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        for r in mapped.chunks_exact(padded as usize) {
            pixels.extend_from_slice(&r[..row as usize]);
        }
    }
    buffer.unmap();
    image::RgbaImage::from_raw(width, height, pixels)
        .ok_or_else(|| RenderError::Readback("pixel buffer of the wrong size".into()))
}

/// sRGB transfer function, decoding.
fn linear_from_srgb(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The app keeps the renderer in egui_wgpu's callback resources (a
    /// type map that needs `Send + Sync`) or behind a lock.
    #[test]
    fn renderer_is_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<Renderer>();
    }

    #[test]
    fn srgb_decoding_fixes_the_ends() {
        assert_eq!(linear_from_srgb(0.0), 0.0);
        assert!((linear_from_srgb(1.0) - 1.0).abs() < 1e-6);
        assert!((linear_from_srgb(0.5) - 0.214).abs() < 1e-3);
    }
}
