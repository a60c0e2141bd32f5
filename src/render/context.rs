//! Context for the meshes: image quads (slices of the volume) and a
//! clipping plane.
//!
//! The renderer knows no volume: a slice is a rectangle in world space
//! with an RGBA image on it ([`SliceQuad`]), made by whoever samples the
//! volume (the explorer, `flexiso render`). Slices are drawn opaque,
//! unlit and depth-tested with the opaque meshes, so a contour crossing
//! a slice shows where it pierces it; they are not clipped (they are the
//! context the cut reveals).
//!
//! A [`ClipPlane`] cuts every mesh: fragments on the side its normal
//! points to are discarded in `mesh.wgsl`, and picking casts only along
//! the part of the ray on the kept side (a half-space meets a ray in one
//! interval, so "the nearest kept hit" is "the nearest hit within that
//! interval"). A [`CutBox`] cuts away what lies inside an axis-aligned
//! box (a corner cut out of a head shows the brain inside): its
//! fragments are discarded too, and since a box meets a ray in one
//! interval, the ray's kept part is at most two intervals, before and
//! after it ([`CutBox::kept_parts`]); the nearest kept hit is the nearest
//! hit within the first of them that has one. Neither cut is capped: one
//! sees into a cut surface, its inside drawn darker by the two-sided
//! lighting.

use std::sync::Arc;

use glam::Vec3;

/// How many slices the renderer holds (one per axis in the explorer).
pub const MAX_SLICES: usize = 3;

/// A plane cutting every mesh: what lies where `normal · p > offset` is
/// neither drawn nor picked.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipPlane {
    /// Points towards the side cut away (need not be unit length).
    pub normal: [f32; 3],
    /// The plane is `normal · p = offset`.
    pub offset: f32,
}

impl ClipPlane {
    /// The plane `p[axis] = at`, cutting away what lies above it
    /// (`keep_below`) or below it.
    pub fn axis(axis: usize, at: f32, keep_below: bool) -> ClipPlane {
        let mut normal = [0.0; 3];
        let s = if keep_below { 1.0 } else { -1.0 };
        normal[axis.min(2)] = s;
        ClipPlane {
            normal,
            offset: s * at,
        }
    }

    /// Whether `p` is kept (drawn).
    pub fn keeps(&self, p: [f32; 3]) -> bool {
        Vec3::from(self.normal).dot(Vec3::from(p)) <= self.offset
    }

    /// The interval `[t0, t1]` of the ray `origin + t dir` (t ≥ 0) on the
    /// kept side, or None when the ray never is.
    pub fn kept_interval(&self, origin: Vec3, dir: Vec3) -> Option<(f32, f32)> {
        let n = Vec3::from(self.normal);
        let s = n.dot(origin) - self.offset;
        let d = n.dot(dir);
        if d.abs() < 1e-12 {
            return (s <= 0.0).then_some((0.0, f32::INFINITY));
        }
        let t = -s / d;
        if d > 0.0 {
            // Moving towards the cut side: kept until t.
            (t >= 0.0).then_some((0.0, t))
        } else {
            Some((t.max(0.0), f32::INFINITY))
        }
    }

    /// As the shader takes it.
    pub(super) fn as_vec4(&self) -> [f32; 4] {
        let [x, y, z] = self.normal;
        [x, y, z, self.offset]
    }
}

/// An axis-aligned box whose inside is cut away from every mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutBox {
    /// The low corner.
    pub lo: [f32; 3],
    /// The high corner.
    pub hi: [f32; 3],
}

impl CutBox {
    /// Whether `p` is kept (drawn): outside the box (its faces count as
    /// inside, as in the shader).
    pub fn keeps(&self, p: [f32; 3]) -> bool {
        !(0..3).all(|a| self.lo[a] <= p[a] && p[a] <= self.hi[a])
    }

    /// Where the line `origin + t dir` is inside the box: `[t_in, t_out]`
    /// (any t, also negative), None when it misses.
    pub fn ray_inside(&self, origin: Vec3, dir: Vec3) -> Option<(f32, f32)> {
        let (mut t_in, mut t_out) = (f32::NEG_INFINITY, f32::INFINITY);
        for a in 0..3 {
            let (o, d) = (origin[a], dir[a]);
            if d.abs() < 1e-12 {
                if o < self.lo[a] || o > self.hi[a] {
                    return None;
                }
                continue;
            }
            let (t0, t1) = ((self.lo[a] - o) / d, (self.hi[a] - o) / d);
            t_in = t_in.max(t0.min(t1));
            t_out = t_out.min(t0.max(t1));
        }
        (t_in <= t_out).then_some((t_in, t_out))
    }

    /// The parts of `[t0, t1]` of the ray `origin + t dir` outside the
    /// box, nearest first (none, one or two, each non-empty).
    pub fn kept_parts(&self, origin: Vec3, dir: Vec3, t0: f32, t1: f32) -> Vec<(f32, f32)> {
        let Some((t_in, t_out)) = self.ray_inside(origin, dir) else {
            return if t0 < t1 { vec![(t0, t1)] } else { Vec::new() };
        };
        [(t0, t1.min(t_in)), (t0.max(t_out), t1)]
            .into_iter()
            .filter(|(a, b)| a < b)
            .collect()
    }
}

/// Vertices a label's anchor is looked for among, at most: every k-th of
/// a bigger mesh (a label needs no exact top, and dragging the clipping
/// plane looks again each frame: a pass over millions of vertices would
/// cost the frame milliseconds).
pub const ANCHOR_CANDIDATES: usize = 65_536;

/// Where a contour's name label goes: the highest point of its mesh that
/// the clipping plane keeps (on top of the surface, seen from the usual
/// views), among at most [`ANCHOR_CANDIDATES`] of its vertices, outside
/// the cut-away box `cut`; None when all of them are cut away.
pub fn label_anchor(
    positions: &[[f32; 3]],
    clip: Option<ClipPlane>,
    cut: Option<CutBox>,
) -> Option<[f32; 3]> {
    let step = positions.len().div_ceil(ANCHOR_CANDIDATES).max(1);
    positions
        .iter()
        .step_by(step)
        .copied()
        .filter(|p| clip.is_none_or(|c| c.keeps(*p)) && cut.is_none_or(|c| c.keeps(*p)))
        .max_by(|a, b| a[2].total_cmp(&b[2]).then(a[1].total_cmp(&b[1])))
}

/// An image on a rectangle of the scene.
#[derive(Clone, Debug)]
pub struct SliceQuad {
    /// The corners in world space, in the order of the image's top-left,
    /// top-right, bottom-right and bottom-left texels.
    pub corners: [[f32; 3]; 4],
    /// sRGB-encoded RGBA (alpha is ignored: slices are opaque).
    pub image: Arc<image::RgbaImage>,
}

impl SliceQuad {
    /// The ray parameter `t > 0` where `origin + t dir` crosses the quad
    /// (two triangles), if it does.
    pub fn ray_hit(&self, origin: Vec3, dir: Vec3) -> Option<f32> {
        let c = self.corners.map(Vec3::from);
        let a = super::geometry::ray_triangle(origin, dir, c[0], c[1], c[2]);
        let b = super::geometry::ray_triangle(origin, dir, c[0], c[2], c[3]);
        match (a, b) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

/// Vertex of a slice quad: position and texture coordinate.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct SliceVertex {
    pub position: [f32; 3],
    pub uv: [f32; 2],
}

/// The slice as the GPU holds it.
pub(super) struct SliceGpu {
    pub texture: wgpu::Texture,
    pub bind: wgpu::BindGroup,
    pub vertices: wgpu::Buffer,
}

/// One slot of the renderer's slices.
#[derive(Default)]
pub(super) struct SliceSlot {
    pub quad: Option<SliceQuad>,
    /// The quad changed since it was uploaded.
    pub dirty: bool,
    pub gpu: Option<SliceGpu>,
}

impl SliceSlot {
    /// Uploads the quad when it changed, reusing the texture when the
    /// image has its size.
    pub fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        layout: &wgpu::BindGroupLayout,
        sampler: &wgpu::Sampler,
    ) {
        if !self.dirty {
            return;
        }
        self.dirty = false;
        let Some(q) = &self.quad else {
            self.gpu = None;
            return;
        };
        let (w, h) = q.image.dimensions();
        if w == 0 || h == 0 {
            self.gpu = None;
            return;
        }
        let uv = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let verts: Vec<SliceVertex> = [0usize, 1, 2, 0, 2, 3]
            .iter()
            .map(|&i| SliceVertex {
                position: q.corners[i],
                uv: uv[i],
            })
            .collect();
        let reuse = self.gpu.take().filter(|g| {
            let s = g.texture.size();
            s.width == w && s.height == h
        });
        let gpu = match reuse {
            Some(g) => g,
            None => {
                let max = device.limits().max_texture_dimension_2d;
                if w > max || h > max {
                    return;
                }
                let texture = device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("flexiso slice"),
                    size: wgpu::Extent3d {
                        width: w,
                        height: h,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::Rgba8Unorm,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                });
                let view = texture.create_view(&Default::default());
                let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("flexiso slice"),
                    layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: wgpu::BindingResource::TextureView(&view),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::Sampler(sampler),
                        },
                    ],
                });
                let vertices = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("flexiso slice vertices"),
                    size: (6 * std::mem::size_of::<SliceVertex>()) as u64,
                    usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                SliceGpu {
                    texture,
                    bind,
                    vertices,
                }
            }
        };
        queue.write_texture(
            gpu.texture.as_image_copy(),
            q.image.as_raw(),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * w),
                rows_per_image: Some(h),
            },
            gpu.texture.size(),
        );
        queue.write_buffer(&gpu.vertices, 0, bytemuck::cast_slice(&verts));
        self.gpu = Some(gpu);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_through_the_cut_away_box_is_kept_before_and_after_it() {
        let cut = CutBox {
            lo: [1.0, -1.0, -1.0],
            hi: [2.0, 1.0, 1.0],
        };
        // Along +x from the origin: inside for x in [1, 2].
        assert_eq!(
            cut.kept_parts(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY),
            vec![(0.0, 1.0), (2.0, f32::INFINITY)]
        );
        // Ending inside the box: only the part before it.
        assert_eq!(
            cut.kept_parts(Vec3::ZERO, Vec3::X, 0.0, 1.5),
            vec![(0.0, 1.0)]
        );
        // Starting inside: only the part after it.
        assert_eq!(
            cut.kept_parts(Vec3::new(1.5, 0.0, 0.0), Vec3::X, 0.0, 10.0),
            vec![(0.5, 10.0)]
        );
        // Missing the box: all of it.
        assert_eq!(
            cut.kept_parts(Vec3::new(0.0, 5.0, 0.0), Vec3::X, 0.0, 3.0),
            vec![(0.0, 3.0)]
        );
        // Pointing away: the box lies behind, all of it is kept.
        assert_eq!(
            cut.kept_parts(Vec3::ZERO, -Vec3::X, 0.0, 3.0),
            vec![(0.0, 3.0)]
        );
        assert!(!cut.keeps([1.5, 0.0, 0.0]) && cut.keeps([0.5, 0.0, 0.0]));
        // A label's anchor leaves the box out.
        let points = [[1.5, 0.0, 0.9], [0.0, 0.0, 0.5]];
        assert_eq!(label_anchor(&points, None, None), Some(points[0]));
        assert_eq!(label_anchor(&points, None, Some(cut)), Some(points[1]));
    }

    #[test]
    fn the_kept_interval_of_a_ray_is_on_the_kept_side() {
        let clip = ClipPlane::axis(0, 1.0, true); // keep x <= 1
        // From x = 0 towards +x: kept until x = 1.
        let (t0, t1) = clip
            .kept_interval(Vec3::ZERO, Vec3::X)
            .expect("starts kept");
        assert_eq!((t0, t1), (0.0, 1.0));
        // From x = 3 towards -x: kept from x = 1 on.
        let (t0, t1) = clip
            .kept_interval(Vec3::new(3.0, 0.0, 0.0), -Vec3::X)
            .expect("reaches the kept side");
        assert_eq!(t0, 2.0);
        assert!(t1.is_infinite());
        // From x = 3 away from the plane: never kept.
        assert!(
            clip.kept_interval(Vec3::new(3.0, 0.0, 0.0), Vec3::X)
                .is_none()
        );
        assert!(clip.keeps([0.5, 9.0, 9.0]) && !clip.keeps([1.5, 0.0, 0.0]));
        let above = ClipPlane::axis(2, 1.0, false); // keep z >= 1
        assert!(above.keeps([0.0, 0.0, 2.0]) && !above.keeps([0.0, 0.0, 0.0]));
    }
}
