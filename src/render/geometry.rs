//! CPU-side geometry: meshes prepared for the GPU (and kept for picking),
//! ray casts, vertex normals and a test sphere.
//!
//! Picking casts the ray on the CPU against every triangle of each mesh
//! whose bounding box the ray enters, nearest box first, stopping once a
//! box starts beyond the nearest hit. This needs no GPU round trip, is exact
//! (on the positions as drawn) and handles transparent meshes; it reads the
//! [`PreparedMesh`] the vertex buffer was filled from (12 bytes per vertex,
//! [`GpuVertex`], and 12 per triangle, the same as the GPU's copy) and
//! costs about 5 ns per triangle tested (rayon splits meshes above
//! [`PARALLEL_TRIANGLES`]).

use crate::contour::TriangleBand;
use glam::{Vec3, Vec3A};
use rayon::prelude::*;

/// Meshes with more triangles than this are ray-tested in parallel.
pub const PARALLEL_TRIANGLES: usize = 200_000;

/// One vertex as the GPU's vertex buffer holds it: 12 bytes instead of
/// the 24 of two `f32` triples, so a contour of millions of triangles
/// costs the UI thread half the copy.
///
/// * **Position:** each coordinate quantised to 16 bits across the mesh's
///   own bounding box (`Unorm16x4`, the fourth unused): the error is at
///   most half a step, `extent / 65535 / 2` per axis (a 200 mm head: 1.5
///   µm, a thousandth of a voxel), far below a pixel at any zoom the
///   explorer offers. The shader maps it back with the box
///   ([`PreparedMesh::dequantise`], the same affine map).
/// * **Normal:** octahedral encoding (Cigolle et al., "A survey of
///   efficient representations for independent unit vectors", JCGT 2014)
///   in two `Snorm16`: the unit sphere unfolded onto a square, at most
///   about 0.005° off.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuVertex {
    /// Quantised position in the mesh's box, 0..=65535 per axis; the
    /// fourth is 0.
    pub position: [u16; 4],
    /// Octahedral unit normal, -32767..=32767 per component.
    pub normal: [i16; 2],
}

/// Largest quantised coordinate.
const Q: f32 = 65535.0;

/// Consecutive triangles whose corners lie within 65,536 vertices of
/// `base`: drawn with 16-bit indices relative to it (`base_vertex` of an
/// indexed draw).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IndexRun {
    /// First index (three per triangle) of the run.
    pub start: u32,
    /// One past its last index.
    pub end: u32,
    /// The vertex its indices count from.
    pub base: u32,
}

/// Triangle corners as the index buffer holds them.
///
/// A contour's triangles come in an order that keeps their corners close
/// in vertex numbering (the sweep's layer order; the flood's depth-first
/// order with vertices numbered as found), so runs of thousands of
/// triangles reach fewer than 65,536 vertices: 6 bytes per triangle
/// instead of 12, in a few dozen draws. Other meshes keep 32-bit indices.
#[derive(Clone, Debug, PartialEq)]
pub enum Corners {
    /// 16-bit indices relative to their run's base vertex; padded with a
    /// zero to an even count (buffer copies go in 4-byte steps).
    Short {
        /// The indices, `runs` laid end to end (plus the pad).
        indices: Vec<u16>,
        /// The runs, ascending, covering every index.
        runs: Vec<IndexRun>,
    },
    /// Absolute 32-bit indices.
    Long(Vec<u32>),
}

/// What one pass over the triangles finds, in parallel stretches of
/// [`SCAN_CHUNK`] corners: the greedy 16-bit runs of [`Corners`], the
/// first corner out of range, and six times the signed volume enclosed
/// (divergence theorem, from `centre`; 0 without one). One pass instead of three over a
/// contour's corners: each is as long as the vertices' own pass.
struct TriangleScan {
    runs: Vec<IndexRun>,
    out_of_range: Option<u32>,
    volume6: f64,
}

/// Corners per stretch of [`TriangleScan`]: runs never cross one, so the
/// stretches are independent.
const SCAN_CHUNK: usize = 3 << 16;

impl TriangleScan {
    fn new(positions: &[[f32; 3]], indices: &[u32], centre: Option<Vec3A>) -> TriangleScan {
        let n = positions.len() as u32;
        let stretch = |c: usize, tris: &[u32]| -> TriangleScan {
            let offset = (c * SCAN_CHUNK) as u32;
            let mut scan = TriangleScan {
                runs: Vec::new(),
                out_of_range: None,
                volume6: 0.0,
            };
            let (mut start, mut lo, mut hi) = (0usize, u32::MAX, 0u32);
            for (t, tri) in tris.chunks_exact(3).enumerate() {
                let tlo = tri[0].min(tri[1]).min(tri[2]);
                let thi = tri[0].max(tri[1]).max(tri[2]);
                if thi >= n {
                    scan.out_of_range.get_or_insert(thi);
                } else if let Some(centre) = centre {
                    // From the first corner: the edges are short, so their
                    // cross product keeps its precision in f32.
                    let p = |k: usize| Vec3A::from(positions[tri[k] as usize]);
                    let (p0, p1, p2) = (p(0), p(1), p(2));
                    let v = (p0 - centre).dot((p1 - p0).cross(p2 - p0));
                    if v.is_finite() {
                        scan.volume6 += v as f64;
                    }
                }
                let (nlo, nhi) = (lo.min(tlo), hi.max(thi));
                if nhi - nlo > u16::MAX as u32 {
                    scan.runs.push(IndexRun {
                        start: offset + start as u32,
                        end: offset + 3 * t as u32,
                        base: lo,
                    });
                    (start, lo, hi) = (3 * t, tlo, thi);
                } else {
                    (lo, hi) = (nlo, nhi);
                }
            }
            if start < tris.len() {
                scan.runs.push(IndexRun {
                    start: offset + start as u32,
                    end: offset + tris.len() as u32,
                    base: lo,
                });
            }
            scan
        };
        if indices.len() <= SCAN_CHUNK {
            return stretch(0, indices);
        }
        let parts: Vec<TriangleScan> = indices
            .par_chunks(SCAN_CHUNK)
            .enumerate()
            .map(|(c, t)| stretch(c, t))
            .collect();
        TriangleScan {
            out_of_range: parts.iter().find_map(|p| p.out_of_range),
            volume6: parts.iter().map(|p| p.volume6).sum(),
            runs: parts.into_iter().flat_map(|p| p.runs).collect(),
        }
    }
}

impl Corners {
    /// Triangle corners in the 16-bit `runs` ([`TriangleScan`]) when runs
    /// average at least [`MIN_RUN_TRIANGLES`] triangles, else 32-bit.
    /// Parallel.
    /// `spare`'s array is reused when it is of the kind needed and large
    /// enough.
    fn new(indices: &[u32], runs: Vec<IndexRun>, spare: Corners) -> Corners {
        let triangles = indices.len() / 3;
        if !short_pays(runs.len(), triangles) {
            let spare_long = match spare {
                Corners::Long(i) => i,
                Corners::Short { .. } => Vec::new(),
            };
            return Corners::Long(crate::pages::copied(spare_long, indices));
        }
        // The scan's runs hold their corners by construction.
        Corners::short(indices, runs, spare, u32::MAX)
            .unwrap_or_else(|_| Corners::Long(indices.to_vec()))
    }

    /// The 16-bit form in `runs` (each covering its corners' ascending
    /// stretch), checking as it writes that every corner lies in its run's
    /// reach and below `vertices`: `Err` with `spare` (as far as it was
    /// used) when one does not.
    fn short(
        indices: &[u32],
        runs: Vec<IndexRun>,
        spare: Corners,
        vertices: u32,
    ) -> Result<Corners, Corners> {
        let spare_short = match spare {
            Corners::Short { indices, .. } => indices,
            Corners::Long(_) => Vec::new(),
        };
        // Every corner is written below; the pad is set here.
        let mut short = crate::pages::reused(spare_short, indices.len() + indices.len() % 2, 0u16);
        if let Some(pad) = short.get_mut(indices.len()) {
            *pad = 0;
        }
        let write = |out: &mut [u16], from: usize| -> bool {
            let mut inside = true;
            // The runs within this stretch of indices.
            let first = runs.partition_point(|r| (r.end as usize) <= from);
            for r in &runs[first..] {
                let (s, e) = (r.start as usize, r.end as usize);
                if s >= from + out.len() {
                    break;
                }
                let (s, e) = (s.max(from), e.min(from + out.len()));
                for (o, &i) in out[s - from..e - from].iter_mut().zip(&indices[s..e]) {
                    let d = i.wrapping_sub(r.base);
                    inside &= (d <= u16::MAX as u32) & (i < vertices);
                    *o = d as u16;
                }
            }
            inside
        };
        let inside = if indices.len() > SCAN_CHUNK {
            short[..indices.len()]
                .par_chunks_mut(SCAN_CHUNK)
                .enumerate()
                .map(|(c, out)| write(out, c * SCAN_CHUNK))
                .reduce(|| true, |a, b| a & b)
        } else {
            write(&mut short[..indices.len()], 0)
        };
        let covered = runs.last().map_or(0, |r| r.end as usize) == indices.len();
        if inside && covered {
            Ok(Corners::Short {
                indices: short,
                runs,
            })
        } else {
            Err(Corners::Short {
                indices: short,
                runs: Vec::new(),
            })
        }
    }

    /// The 16-bit runs of a mesh whose maker gave its [`TriangleBand`]s:
    /// consecutive bands joined while the vertices they reach span at most
    /// 65,536, with no pass over the corners. None when the bands do not
    /// cover the `corners` in order, one band alone spans more, or the
    /// runs are too short to pay ([`MIN_RUN_TRIANGLES`]).
    fn runs_of_bands(bands: &[TriangleBand], corners: usize) -> Option<Vec<IndexRun>> {
        let reach = u16::MAX as u32 + 1;
        let mut runs: Vec<IndexRun> = Vec::new();
        // The open run and the end of the vertices it reaches.
        let mut open: Option<(IndexRun, u32)> = None;
        let mut next = 0u32;
        for b in bands {
            let (c, v) = (&b.corners, &b.vertices);
            if c.start != next || c.end < c.start || v.end < v.start || v.end - v.start > reach {
                return None;
            }
            next = c.end;
            if c.is_empty() {
                continue;
            }
            open = Some(match open {
                Some((run, end)) if v.start >= run.base && v.end.max(end) - run.base <= reach => {
                    (IndexRun { end: c.end, ..run }, v.end.max(end))
                }
                other => {
                    runs.extend(other.map(|(run, _)| run));
                    let run = IndexRun {
                        start: c.start,
                        end: c.end,
                        base: v.start,
                    };
                    (run, v.end)
                }
            });
        }
        runs.extend(open.map(|(run, _)| run));
        (next as usize == corners && short_pays(runs.len(), corners / 3)).then_some(runs)
    }

    /// Number of triangle corners (three per triangle).
    pub fn len(&self) -> usize {
        match self {
            Corners::Short { runs, .. } => runs.last().map_or(0, |r| r.end as usize),
            Corners::Long(i) => i.len(),
        }
    }

    /// True when there is no triangle.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The bytes of the index buffer.
    pub fn bytes(&self) -> &[u8] {
        match self {
            Corners::Short { indices, .. } => bytemuck::cast_slice(indices),
            Corners::Long(i) => bytemuck::cast_slice(i),
        }
    }

    /// Every triangle's corners as absolute vertex indices, in order.
    pub fn to_absolute(&self) -> Vec<u32> {
        match self {
            Corners::Short { indices, runs } => runs
                .iter()
                .flat_map(|r| {
                    indices[r.start as usize..r.end as usize]
                        .iter()
                        .map(move |&i| r.base + i as u32)
                })
                .collect(),
            Corners::Long(i) => i.clone(),
        }
    }

    /// The corner ranges and the base vertex each counts from.
    fn runs(&self) -> Vec<(std::ops::Range<usize>, u32)> {
        match self {
            Corners::Short { runs, .. } => runs
                .iter()
                .map(|r| (r.start as usize..r.end as usize, r.base))
                .collect(),
            Corners::Long(i) => vec![(0..i.len(), 0)],
        }
    }

    /// Corner `k` (an index into the corners) as an absolute vertex index,
    /// within a run of base `base`.
    #[inline]
    fn corner(&self, k: usize, base: u32) -> u32 {
        match self {
            Corners::Short { indices, .. } => base + indices[k] as u32,
            Corners::Long(i) => i[k],
        }
    }
}

/// Fewest triangles per 16-bit run on average for [`Corners::Short`].
pub const MIN_RUN_TRIANGLES: usize = 1024;

/// Whether `runs` 16-bit runs over `triangles` triangles pay for their
/// draws (one run always does).
fn short_pays(runs: usize, triangles: usize) -> bool {
    runs <= 1 || runs * MIN_RUN_TRIANGLES <= triangles
}

/// `n` (any length) in the octahedral encoding of [`GpuVertex::normal`];
/// a zero or non-finite vector becomes +z.
#[inline]
pub fn encode_normal(n: [f32; 3]) -> [i16; 2] {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    let valid = (l1 > 0.0) & l1.is_finite();
    let (x, y) = (n[0] / l1, n[1] / l1);
    let sign = |v: f32| if v >= 0.0 { 1.0 } else { -1.0 };
    let folded = ((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y));
    let (x, y) = if n[2] < 0.0 { folded } else { (x, y) };
    // Round half away from zero without a libm call (the cast truncates;
    // a NaN casts to 0).
    let e = [x, y].map(|v| {
        let v = v.clamp(-1.0, 1.0) * 32767.0;
        (v + 0.5f32.copysign(v)) as i16
    });
    if valid { e } else { [0, 0] }
}

/// Writes each position quantised in the box from `origin` at `step` per
/// unit (a non-finite coordinate casts to 0), and its normal octahedral,
/// into `out`.
fn quantise_vertices(
    out: &mut [GpuVertex],
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    origin: [f32; 3],
    step: [f32; 3],
) {
    for (o, (p, nr)) in out.iter_mut().zip(positions.iter().zip(normals)) {
        let q: [u16; 3] = std::array::from_fn(|a| {
            let q = ((p[a] - origin[a]) * step[a]).clamp(0.0, Q);
            // Rounding of a non-negative value without a libm call (the
            // cast truncates): a third of the pass otherwise.
            (q + 0.5) as u16
        });
        *o = GpuVertex {
            position: [q[0], q[1], q[2], 0],
            normal: encode_normal(*nr),
        };
    }
}

/// The unit vector of an octahedral [`GpuVertex::normal`] (what the vertex
/// shader computes).
pub fn decode_normal(e: [i16; 2]) -> [f32; 3] {
    let (x, y) = (
        (e[0] as f32 / 32767.0).max(-1.0),
        (e[1] as f32 / 32767.0).max(-1.0),
    );
    let z = 1.0 - x.abs() - y.abs();
    let t = (-z).max(0.0);
    let n = Vec3::new(
        x + if x >= 0.0 { -t } else { t },
        y + if y >= 0.0 { -t } else { t },
        z,
    );
    n.normalize_or(Vec3::Z).to_array()
}

/// What a mesh's maker knows of it without a pass over its arrays (see
/// [`PreparedMesh::new_known`]); [`Known::default`] knows nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Known<'a> {
    /// Whether its triangles wind counter-clockwise seen from outside
    /// ([`crate::contour::ContourMesh::ccw_outward`]): spares the signed
    /// volume's gathers. The bands are only read when this is known.
    pub ccw_outward: Option<bool>,
    /// The box of its positions ([`crate::contour::ContourMesh::bounds`]).
    pub bounds: Option<[[f32; 3]; 2]>,
    /// Its triangle bands ([`crate::contour::ContourMesh::bands`]): spare
    /// the pass that finds the 16-bit runs.
    pub bands: &'a [TriangleBand],
}

impl<'a> From<&'a crate::contour::ContourMesh> for Known<'a> {
    fn from(m: &'a crate::contour::ContourMesh) -> Self {
        Known {
            ccw_outward: m.ccw_outward,
            bounds: m.bounds,
            bands: &m.bands,
        }
    }
}

/// A mesh made ready for the GPU: validated, normals computed when it came
/// without, vertices quantised as the vertex buffer holds them
/// ([`GpuVertex`]), with its box. Building one costs a few passes over the
/// mesh (in parallel), so the app builds it on the thread that extracted
/// the contour and the UI thread only copies bytes
/// ([`Renderer::set_prepared_mesh`]). The renderer keeps it (shared) as
/// its CPU copy for picking, which reads the dequantised positions.
///
/// [`Renderer::set_prepared_mesh`]: super::Renderer::set_prepared_mesh
#[derive(Clone, Debug, PartialEq)]
pub struct PreparedMesh {
    /// The vertices, quantised in `bbox`.
    pub(crate) vertices: Vec<GpuVertex>,
    /// Triangle corners, three per triangle, each `< vertices.len()`.
    pub(crate) indices: Corners,
    /// Axis-aligned bounding box (min, max) of the vertices as given;
    /// inverted (min > max) when empty.
    pub(crate) bbox: (Vec3, Vec3),
    /// Whether counter-clockwise triangles face outwards: the signed volume
    /// enclosed is positive. Exact for closed meshes, a majority vote for
    /// open ones; decides the draw order of a transparent mesh's halves.
    pub(crate) ccw_outward: bool,
}

impl Default for PreparedMesh {
    fn default() -> Self {
        PreparedMesh {
            vertices: Vec::new(),
            indices: Corners::Long(Vec::new()),
            bbox: bbox_of(&[], &[]),
            ccw_outward: true,
        }
    }
}

impl PreparedMesh {
    /// A GPU form with room for a mesh of `vertices` and `triangles` and a
    /// quarter more, its pages already touched, to be reused by
    /// [`PreparedMesh::new_known`] (see [`crate::contour::ContourMesh::spare`]).
    pub fn spare(vertices: usize, triangles: usize) -> Self {
        PreparedMesh {
            vertices: crate::pages::spare(vertices),
            indices: Corners::Short {
                indices: crate::pages::spare(3 * triangles + 1),
                runs: Vec::new(),
            },
            ..Self::default()
        }
    }
}

/// Meshes with fewer vertices than this are prepared on one thread.
const PARALLEL_VERTICES: usize = 1 << 15;

impl PreparedMesh {
    /// Checks and quantises a mesh. `normals` has one normal per position,
    /// or is empty to have them computed from the triangles
    /// ([`compute_normals`]); `indices` holds three corners per triangle.
    /// The error says what is malformed. Parallel (rayon) for large meshes.
    pub fn new(
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        indices: &[u32],
    ) -> Result<Self, String> {
        Self::new_reusing(positions, normals, indices, PreparedMesh::default())
    }

    /// [`PreparedMesh::new`], written into `spare`'s arrays where they are
    /// large enough (a mesh already uploaded and let go: see
    /// [`crate::pages::refilled`]); the result is the same.
    pub fn new_reusing(
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        indices: &[u32],
        spare: PreparedMesh,
    ) -> Result<Self, String> {
        Self::new_known(positions, normals, indices, Known::default(), spare)
    }

    /// [`PreparedMesh::new_reusing`] told what the mesh's maker knows of it
    /// ([`Known`]): each thing known spares a pass over the mesh (a
    /// 5.4 M-triangle head from the sweep: 45 ms to prepare, 19 ms with
    /// all three known). The result is the same mesh; only its 16-bit runs
    /// may be cut elsewhere.
    pub fn new_known(
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        indices: &[u32],
        known: Known<'_>,
        spare: PreparedMesh,
    ) -> Result<Self, String> {
        if !normals.is_empty() && normals.len() != positions.len() {
            return Err(format!(
                "{} normals for {} positions",
                normals.len(),
                positions.len()
            ));
        }
        if !indices.len().is_multiple_of(3) {
            return Err(format!(
                "{} indices is not a whole number of triangles",
                indices.len()
            ));
        }
        if indices.len() > u32::MAX as usize {
            return Err(format!(
                "{} triangles are too many to draw",
                indices.len() / 3
            ));
        }
        let n = positions.len();
        let bbox = match known.bounds {
            Some([lo, hi]) if !indices.is_empty() => (Vec3::from(lo), Vec3::from(hi)),
            _ => bbox_of(positions, indices),
        };
        // The corners in the bands' 16-bit runs, checked as they are
        // written; a scan of the triangles otherwise, or when one fails.
        let (banded, spare_corners) = match (known.ccw_outward, n > u32::MAX as usize) {
            (Some(_), false) => match Corners::runs_of_bands(known.bands, indices.len()) {
                Some(runs) => match Corners::short(indices, runs, spare.indices, n as u32) {
                    Ok(c) => (Some(c), Corners::Long(Vec::new())),
                    Err(spare) => (None, spare),
                },
                None => (None, spare.indices),
            },
            _ => (None, spare.indices),
        };
        let (indices_out, volume6) = match banded {
            Some(c) => (c, 0.0),
            None => {
                let centre = if bbox.0.cmple(bbox.1).all() {
                    0.5 * (bbox.0 + bbox.1)
                } else {
                    Vec3::ZERO
                };
                let centre = known.ccw_outward.is_none().then_some(centre.into());
                let scan = TriangleScan::new(positions, indices, centre);
                if let Some(bad) = scan.out_of_range {
                    return Err(format!(
                        "index {bad} is out of range for {} positions",
                        positions.len()
                    ));
                }
                (
                    Corners::new(indices, scan.runs, spare_corners),
                    scan.volume6,
                )
            }
        };
        let computed;
        let normals = if normals.is_empty() {
            computed = compute_normals(positions, indices);
            &computed[..]
        } else {
            normals
        };
        let (origin, step) = quantisation(bbox);
        let quantise = |out: &mut [GpuVertex], p: &[[f32; 3]], nr: &[[f32; 3]]| {
            quantise_vertices(out, p, nr, origin.to_array(), step.to_array());
        };
        let parallel = n > PARALLEL_VERTICES;
        let vertices = if parallel {
            // Written in place into huge pages: a fresh page's first touch
            // costs as much as the quantising.
            // Every vertex is written below.
            let mut v = crate::pages::reused(spare.vertices, n, GpuVertex::default());
            v.par_chunks_mut(1 << 14)
                .zip(
                    positions
                        .par_chunks(1 << 14)
                        .zip(normals.par_chunks(1 << 14)),
                )
                .for_each(|(out, (p, nr))| quantise(out, p, nr));
            v
        } else {
            let mut v = vec![GpuVertex::default(); n];
            quantise(&mut v, positions, normals);
            v
        };
        Ok(PreparedMesh {
            vertices,
            indices: indices_out,
            bbox,
            ccw_outward: known.ccw_outward.unwrap_or(volume6 >= 0.0),
        })
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.indices.len() / 3
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// The bounding box `(min, max)` the positions are quantised in, or
    /// None for a mesh without triangles.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let (lo, hi) = self.bbox;
        lo.cmple(hi).all().then(|| (lo.to_array(), hi.to_array()))
    }

    /// Bytes the GPU buffers take (vertices and indices).
    pub fn gpu_bytes(&self) -> u64 {
        (std::mem::size_of_val(&self.vertices[..]) + self.indices.bytes().len()) as u64
    }

    /// The triangle corners as the index buffer holds them.
    pub fn corners(&self) -> &Corners {
        &self.indices
    }

    /// The quantised vertices as the vertex buffer holds them.
    pub fn gpu_vertices(&self) -> &[GpuVertex] {
        &self.vertices
    }

    /// The affine map from quantised to world positions: `world = origin +
    /// q * scale` per axis (what the vertex shader applies, with `q` in
    /// 0..=65535).
    pub fn dequantise(&self) -> (Vec3, Vec3) {
        let (origin, step) = quantisation(self.bbox);
        let scale = Vec3::select(step.cmpgt(Vec3::ZERO), step.recip(), Vec3::ZERO);
        (origin, scale)
    }

    /// Vertex `i`'s position and unit normal as the GPU sees them.
    pub fn vertex(&self, i: usize) -> ([f32; 3], [f32; 3]) {
        let (origin, scale) = self.dequantise();
        let v = &self.vertices[i];
        let q = Vec3::new(
            v.position[0] as f32,
            v.position[1] as f32,
            v.position[2] as f32,
        );
        ((origin + q * scale).to_array(), decode_normal(v.normal))
    }

    fn position(&self, i: u32, origin: Vec3, scale: Vec3) -> Vec3 {
        let v = &self.vertices[i as usize].position;
        origin + Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32) * scale
    }

    /// Centre of the bounding box (for back-to-front sorting).
    pub fn centre(&self) -> Vec3 {
        if self.bbox.0.cmple(self.bbox.1).all() {
            0.5 * (self.bbox.0 + self.bbox.1)
        } else {
            Vec3::ZERO
        }
    }

    /// The nearest hit of the ray `origin + t dir` (t > 0) with the mesh
    /// (its positions as drawn): `(t, point)`.
    pub fn ray_hit(&self, origin: Vec3, dir: Vec3) -> Option<(f32, Vec3)> {
        let (o, scale) = self.dequantise();
        let corners = &self.indices;
        let parallel = corners.len() / 3 > PARALLEL_TRIANGLES;
        let best = corners
            .runs()
            .into_iter()
            .filter_map(|(range, base)| {
                let test = |t: usize| -> Option<f32> {
                    let p = |k: usize| self.position(corners.corner(3 * t + k, base), o, scale);
                    ray_triangle(origin, dir, p(0), p(1), p(2))
                };
                let triangles = range.start / 3..range.end / 3;
                if parallel {
                    triangles
                        .into_par_iter()
                        .filter_map(test)
                        .reduce_with(f32::min)
                } else {
                    triangles.filter_map(test).reduce(f32::min)
                }
            })
            .reduce(f32::min);
        best.map(|t| (t, origin + t * dir))
    }
}

/// The box's corner and the steps per unit of each axis that map it onto
/// 0..=65535 (0 along an axis of no extent, or with no box).
fn quantisation((lo, hi): (Vec3, Vec3)) -> (Vec3, Vec3) {
    if !lo.cmple(hi).all() {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let extent = hi - lo;
    let step = Vec3::select(extent.cmpgt(Vec3::ZERO), Q / extent, Vec3::ZERO);
    (lo, Vec3::select(step.is_finite_mask(), step, Vec3::ZERO))
}

/// The bounding box of the finite vertices (inverted when there are no
/// triangles).
fn bbox_of(positions: &[[f32; 3]], indices: &[u32]) -> (Vec3, Vec3) {
    let empty = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    if indices.is_empty() {
        return empty;
    }
    let add = |(lo, hi): (Vec3, Vec3), p: &[f32; 3]| {
        let p = Vec3::from(*p);
        if p.is_finite() {
            (lo.min(p), hi.max(p))
        } else {
            (lo, hi)
        }
    };
    if positions.len() > PARALLEL_VERTICES {
        positions
            .par_chunks(1 << 14)
            .map(|c| c.iter().fold(empty, add))
            .reduce(|| empty, |a, b| (a.0.min(b.0), a.1.max(b.1)))
    } else {
        positions.iter().fold(empty, add)
    }
}

/// Where the ray enters the box: the smallest `t ≥ 0` inside it, or None
/// when it misses (slab test; an inverted box is always missed).
pub(crate) fn ray_box(origin: Vec3, dir: Vec3, lo: Vec3, hi: Vec3) -> Option<f32> {
    if !lo.cmple(hi).all() {
        return None;
    }
    // A huge finite reciprocal instead of ∞ keeps 0·∞ = NaN out when the
    // ray lies in a slab's plane.
    let inv = Vec3::select(dir.cmpeq(Vec3::ZERO), Vec3::splat(1e30), dir.recip());
    let t0 = (lo - origin) * inv;
    let t1 = (hi - origin) * inv;
    let tmin = t0.min(t1);
    let tmax = t0.max(t1);
    let enter = tmin.max_element().max(0.0);
    let exit = tmax.min_element();
    (enter <= exit).then_some(enter)
}

/// Möller–Trumbore ray–triangle intersection, both faces: the ray
/// parameter `t > 0` of the hit, if any.
pub(crate) fn ray_triangle(origin: Vec3, dir: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f32> {
    let e1 = b - a;
    let e2 = c - a;
    let p = dir.cross(e2);
    let det = e1.dot(p);
    // Relative threshold: the determinant scales with the triangle's area.
    if det.abs() <= 1e-12 * e1.length_squared().max(e2.length_squared()) || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv;
    if !(-1e-6..=1.0 + 1e-6).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < -1e-6 || u + v > 1.0 + 1e-6 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t)
}

/// Area-weighted unit vertex normals, for meshes that come without: the
/// same function contour extraction starts its normals from (one
/// definition, [`crate::contour::follow::vertex_normals`]). The
/// orientation follows the winding: counter-clockwise triangles face
/// their normal; a vertex no triangle of non-zero area uses gets +z.
pub use crate::contour::follow::vertex_normals as compute_normals;

/// A sphere mesh (icosahedron subdivided `subdivisions` times, vertices
/// pushed to the sphere): `(positions, normals, indices)`, outward normals
/// and counter-clockwise winding seen from outside. For tests and demos;
/// 20·4ⁿ triangles.
pub fn icosphere(
    centre: [f32; 3],
    radius: f32,
    subdivisions: u32,
) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let mut verts: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vec3::from(*p).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, verts: &mut Vec<Vec3>| -> u32 {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                verts.push((0.5 * (verts[a as usize] + verts[b as usize])).normalize());
                (verts.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = mid(a, b, &mut verts);
            let bc = mid(b, c, &mut verts);
            let ca = mid(c, a, &mut verts);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let centre = Vec3::from(centre);
    let positions = verts
        .iter()
        .map(|n| (centre + radius * *n).to_array())
        .collect();
    let normals = verts.iter().map(|n| n.to_array()).collect();
    (positions, normals, tris.into_iter().flatten().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_hits_the_near_side_of_a_sphere() {
        let (p, _, i) = icosphere([0.0, 0.0, 0.0], 1.0, 3);
        let m = PreparedMesh::new(&p, &[], &i).expect("a valid mesh");
        let (t, hit) = m
            .ray_hit(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0))
            .expect("hit");
        assert!((t - 4.0).abs() < 0.01, "{t}");
        assert!((hit.z - 1.0).abs() < 0.01);
        assert!(
            m.ray_hit(Vec3::new(2.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0))
                .is_none()
        );
    }

    #[test]
    fn winding_orientation_is_detected() {
        let (p, _, mut i) = icosphere([5.0, 0.0, 0.0], 1.0, 1);
        assert!(
            PreparedMesh::new(&p, &[], &i)
                .expect("a valid mesh")
                .ccw_outward
        );
        for t in i.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        assert!(
            !PreparedMesh::new(&p, &[], &i)
                .expect("a valid mesh")
                .ccw_outward
        );
    }

    #[test]
    fn ray_box_enters_and_misses() {
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        let t = ray_box(Vec3::new(0.5, 0.5, -1.0), Vec3::Z, lo, hi);
        assert_eq!(t, Some(1.0));
        assert_eq!(ray_box(Vec3::new(2.0, 0.5, -1.0), Vec3::Z, lo, hi), None);
        // Inside the box the entry is the origin.
        assert_eq!(ray_box(Vec3::splat(0.5), Vec3::X, lo, hi), Some(0.0));
    }

    #[test]
    fn computed_normals_of_a_sphere_point_outward() {
        let (p, n0, i) = icosphere([1.0, 2.0, 3.0], 2.0, 2);
        let n = compute_normals(&p, &i);
        for (a, b) in n.iter().zip(&n0) {
            assert!(Vec3::from(*a).dot(Vec3::from(*b)) > 0.99);
        }
    }
}
