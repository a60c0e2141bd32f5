//! The wgpu renderer: lit triangle meshes drawn into an offscreen texture.
//!
//! Like rerun's `re_renderer`, it knows nothing of contour trees or of the
//! UI: it holds meshes keyed by a `u64` id with a style each, and draws them
//! from a [`Camera`] into its own colour and depth textures. The same code
//! serves the egui 3D view, `flexiso render` ([`headless`]) and the tests.
//!
//! # Using it
//! ```text
//! let mut r = Renderer::new(&device, Renderer::sample_count_for(&adapter));
//! r.set_mesh(&device, &queue, id, &positions, &normals, &indices)?; // when the contour changes
//! r.set_style(id, [0.9, 0.5, 0.2, 1.0], true, false);              // cheap, any time
//! r.set_bounds(volume_min, volume_max);
//! let mut camera = Camera::default();
//! camera.fit(volume_min, volume_max);
//! r.render(&device, &queue, &camera, width_px, height_px);          // each frame
//! let hit = r.pick(&camera, w, h, pointer_x, pointer_y);           // Some((id, position))
//! ```
//!
//! **In egui** (eframe with the `wgpu` renderer): keep the [`Renderer`],
//! the [`Camera`] and an [`EguiTexture`] in the 3D view panel. Each frame,
//! with `rs = frame.wgpu_render_state()` (an `Option`; without it show a
//! message instead of the view):
//! ```text
//! let size_px = (rect.size() * ui.pixels_per_point()).round();
//! let (w, h) = (size_px.x as u32, size_px.y as u32);
//! if !renderer.is_current(&camera, w, h) { renderer.render(&rs.device, &rs.queue, &camera, w, h); }
//! let id = tex.update(&mut rs.renderer.write(), &rs.device, &renderer);
//! if let Some(id) = id { ui.put(rect, egui::Image::new((id, rect.size()))); }
//! ```
//! `render` submits its own command buffer, which the queue runs before
//! egui's, so no paint callback is needed. (Inside a paint callback's
//! `prepare`, use [`Renderer::render_with_encoder`] instead; the texture id
//! must then be registered outside, e.g. after the first frame.) Mouse:
//! drag → [`Camera::orbit`], secondary drag → [`Camera::pan`], scroll →
//! [`Camera::zoom`], click → [`Renderer::pick`] with the pointer in the
//! rect's own coordinates and the rect's size (points are fine: only the
//! ratios matter).
//!
//! # Conventions
//! - Colours are **sRGB** in `[0, 1]` with straight alpha, like
//!   `egui::Color32::to_normalized_gamma_f32()`; lighting happens in linear
//!   space. The output texture is [`COLOUR_FORMAT`] (`Rgba8Unorm`) holding
//!   sRGB-encoded bytes: what egui samples from a native texture and what
//!   a PNG stores, so both show the same colours.
//! - World up is +Z; see [`Camera`]. Depth is reversed (near = 1, cleared
//!   to 0, `GreaterEqual` test) in a `Depth32Float` buffer, so zooming in
//!   close does not cost depth precision.
//! - Opaque meshes (alpha = 1) are drawn first with depth writes; then the
//!   bounding box; then transparent meshes back to front by the distance of
//!   their box centre from the eye, depth-tested but not depth-writing.
//!   Transparency within one mesh is not sorted (order-independent
//!   transparency is left out).
//! - Lighting is two-sided: a headlight with a specular spot, plus a fill
//!   light from the upper left; the side a normal points away from is
//!   darker. Normals need not be consistent with the triangle winding.
//! - Slices ([`SliceQuad`], [`Renderer::set_slice`]) are opaque textured
//!   quads drawn after the opaque meshes; a [`ClipPlane`]
//!   ([`Renderer::set_clip`]) cuts every mesh, in the fragment shader and
//!   in picking (see [`context`]).
//! - Meshes, the box, slices and the clip are given in a *model frame*
//!   that [`Renderer::set_placement`] puts in the world by one affine map
//!   (for a volume, its grid frame into the scanner's coordinates): the
//!   camera, lighting and picking's answers are in the world, the clip
//!   and the slices follow the model's axes.
//! - MSAA 4× when [`Renderer::sample_count_for`] says the adapter can.
//! - Geometry is uploaded only by [`Renderer::set_mesh`] (at once) or by
//!   [`Renderer::set_prepared_mesh`] + [`Renderer::upload_pending`] (a
//!   [`PreparedMesh`] built on another thread, copied within a byte budget
//!   per frame, the old geometry drawn until the new is complete); styles,
//!   bounds and camera changes cost a uniform write. Picking is a CPU ray
//!   cast against the prepared mesh the renderer keeps, see [`geometry`]
//!   for the cost.

mod camera;
pub mod context;
mod egui_texture;
pub mod geometry;
pub mod headless;
pub mod overlay;
mod renderer;

pub use camera::{Camera, ViewPreset};
pub use context::{ClipPlane, CutBox, SliceQuad, label_anchor};
pub use egui_texture::EguiTexture;
pub use geometry::{Known, PreparedMesh, compute_normals, icosphere};
pub use headless::{Gpu, HeadlessMesh, HeadlessScene, render_scene_to_image, render_to_image};
pub use renderer::{
    COLOUR_FORMAT, DEFAULT_BACKGROUND, DEFAULT_COLOUR, DEPTH_FORMAT, MeshStyle, Renderer,
    placed_box,
};

/// A renderer mesh, named by whoever adds it (the explorer maps its
/// contours to these; the renderer only keeps them apart).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MeshId(pub u64);

impl From<u64> for MeshId {
    fn from(id: u64) -> Self {
        MeshId(id)
    }
}

/// Compares with a bare number (tests and scripts that name meshes 1, 2, …).
impl PartialEq<u64> for MeshId {
    fn eq(&self, other: &u64) -> bool {
        self.0 == *other
    }
}

impl std::fmt::Display for MeshId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// Distinct sRGB colours for contours, the same in the explorer and in
/// `flexiso render`: contour `i` takes `PALETTE[i % PALETTE.len()]`.
pub const PALETTE: [[u8; 3]; 10] = [
    [228, 115, 51],
    [77, 153, 217],
    [115, 191, 89],
    [217, 89, 140],
    [230, 191, 64],
    [140, 115, 204],
    [89, 191, 191],
    [191, 140, 102],
    [170, 170, 80],
    [200, 120, 220],
];

/// Colour `i` of [`PALETTE`] as the renderer takes it (sRGB in `[0, 1]`,
/// opaque).
pub fn palette_rgba(i: usize) -> [f32; 4] {
    let [r, g, b] = PALETTE[i % PALETTE.len()];
    [
        f32::from(r) / 255.0,
        f32::from(g) / 255.0,
        f32::from(b) / 255.0,
        1.0,
    ]
}

/// The box a grid of `dims` samples `spacing` apart fills, in the grid
/// frame (sample `(0, 0, 0)` at the origin, axes along x, y, z): what
/// the views draw faint, as the renderer's model frame
/// ([`Renderer::set_placement`] puts it in the world).
pub fn grid_bounds(dims: [usize; 3], spacing: [f64; 3]) -> ([f32; 3], [f32; 3]) {
    let extent = |i: usize| ((dims[i].max(1) - 1) as f64 * spacing[i]) as f32;
    ([0.0; 3], [extent(0), extent(1), extent(2)])
}

/// Where the views put the grid frame: the field's world placement
/// ([`crate::field::Geometry::affine`], the map exports use), so the
/// window and `flexiso render` show what `extract` writes
/// (`--space world`).
pub fn placement(field: &crate::field::ScalarField) -> glam::Mat4 {
    let m = field.geometry().affine();
    glam::Mat4::from_cols_array_2d(&m.map(|c| c.map(|x| x as f32)))
}

/// What can go wrong while rendering.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// No graphics adapter was found.
    #[error(
        "no graphics adapter found ({0}); on a machine without a GPU install Mesa's \
         software drivers (apt-get install mesa-vulkan-drivers libvulkan1)"
    )]
    NoAdapter(String),
    /// The adapter refused to open a device.
    #[error("the graphics adapter refused to open a device: {0}")]
    NoDevice(String),
    /// A mesh handed to [`Renderer::set_mesh`] is malformed.
    #[error("mesh {id}: {reason}")]
    InvalidMesh {
        /// The mesh id.
        id: MeshId,
        /// What is wrong with it.
        reason: String,
    },
    /// [`Renderer::read_image`] was called before any render.
    #[error("nothing has been rendered yet")]
    NothingRendered,
    /// Copying the image back from the GPU failed.
    #[error("reading the rendered image back failed: {0}")]
    Readback(String),
}
