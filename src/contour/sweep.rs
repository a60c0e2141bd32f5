//! Every contour at one isovalue by one parallel sweep over the volume:
//! the fast path of [`all_contours`](super::all_contours).
//!
//! Following each contour from its path seed costs time proportional to
//! the contour, which is what picking one arc wants. The whole isosurface
//! is another matter: on a brain scan one contour holds almost every
//! triangle, so following runs on one core however many contours there
//! are. Here the volume is cut into slabs of cube layers that the cores
//! march at once, and the contours are told apart afterwards:
//!
//! 1. **Crossed edges, plane by plane.** A mesh edge `(v, v + d)` (`d` one
//!    of the seven 0/1 offsets: every edge of the Freudenthal mesh once)
//!    belongs to the plane of `v`, its lower end, and is crossed when its
//!    ends lie on either side of the cut. One byte per vertex, the corners
//!    of its cube above the cut, says which; counting them per row numbers
//!    every contour vertex (in order of lower end, then offset) without a
//!    list of edges. A row of cubes whose four vertex rows lie wholly on
//!    one side of the cut (known from one sum over each vertex row's
//!    side bytes) has masks 0 or 0xff, written by a fill, and every later
//!    pass skips it (the rows of air around a scanned head, for one).
//! 2. **Triangles, slab by slab.** A cube layer reads the vertex ids of the
//!    edges owned by its two planes from a dense table per plane, refilled
//!    from the cube bytes (never cleared: only crossed edges are read). The
//!    case tables are the follower's, so winding and interpolation agree
//!    triangle for triangle. Triangles are counted per layer first and
//!    written straight into one array.
//! 3. **Components** by union-find: inside a slab on the slab's own
//!    vertices (in parallel), then the layers that join two slabs from
//!    their triangles. Linking the larger root under the smaller makes
//!    every parent smaller than its child, so one ascending pass labels
//!    everything.
//! 4. **Arcs.** A component is the contour of the superarc whose path seed
//!    lies on it: the seed's edge is numbered from its row's count. The
//!    tree promises one component per spanning arc; if that ever failed,
//!    the caller falls back to following, never to a wrong label.
//!
//! **One contour on every core** ([`contour_by_sweep`], what
//! [`ContourFollower::extract`](super::ContourFollower::extract) uses for
//! a large contour) needs no components: the tree says which side of that
//! contour every vertex lies on ([`CutSides`]: the image of a mesh edge in
//! the tree is a monotone path, so an edge joins the two sides exactly
//! when it crosses this contour). Steps 1 and 2 run on the side bit in
//! place of "above the cut", so the edges and tetrahedra marched are this
//! contour's alone, with the same cases (on them the two bits agree); then
//! positions and gradients plane by plane (the field's gradient once per
//! grid vertex, [`EndGradients`]) and the area-weighted normals slab by
//! slab. Cost: one pass over the volume's values and places (5 bytes per
//! vertex for 8-bit values) plus this contour's own triangles, spread over
//! the cores; the tables are kept from call to call ([`SweepScratch`]).
//! (Until 2026-12-05 it marched the whole isosurface, joined components by
//! union-find while marching and compacted the seed's: on colin27 the
//! head's contour is 97 % of the isosurface, but a contour of a million
//! triangles beside it paid for all 5.5 million.)
//!
//! **Memory is time here:** the first touch of a fresh page costs about as
//! much as the work done on it, so the largest contour (on a scan, nearly
//! all of the isosurface) is compacted in place in the sweep's own arrays
//! instead of copied out, and nothing per edge is kept but the outputs:
//! beyond them, two bytes per volume vertex (which side of the cut, the
//! cube masks), 13 bytes per contour vertex (downhill gradient, face flag;
//! the whole isosurface also a root and a label) and two dense tables of
//! one plane per worker.

use super::marching::{
    Cancelled, TetTables, area_normal, choose_normals, downhill_vector, edge_fraction, end_gradient,
};
use super::seed::CutSides;
use super::{ContourMesh, PathSeed, TriangleBand};
use crate::field::Isovalue;
use crate::field::{Scalar, ScalarField};
use crate::mesh::CUBE_TETRAHEDRA;
use crate::tree::{ArcId, ContourTree};
use rayon::prelude::*;
use std::sync::OnceLock;

/// One triangle corner of a marching-tetrahedra case, as the edge it lies
/// on: the cube corner (bit mask) owning the edge and the edge's offset
/// (bit mask) from it.
type CornerEdge = (u8, u8);

/// Per tetrahedron of the cube: its local mask from the cube's mask of
/// corners above the cut, and its triangles per local mask.
struct SweepTables {
    /// `tet_mask[p][cube]`: bit `l` set when local corner `l` of
    /// tetrahedron `p` is above.
    tet_mask: [[u8; 256]; 6],
    /// `pieces[p][mask]`: up to two triangles, three corner edges each.
    pieces: [[([[CornerEdge; 3]; 2], u8); 16]; 6],
    /// Triangles in a cube, per cube mask.
    triangles: [u8; 256],
}

impl SweepTables {
    fn get() -> &'static SweepTables {
        static T: OnceLock<SweepTables> = OnceLock::new();
        T.get_or_init(|| {
            let cases = &TetTables::get().cases;
            let mut tet_mask = [[0u8; 256]; 6];
            let mut pieces = [[([[(0u8, 0u8); 3]; 2], 0u8); 16]; 6];
            for (p, corners) in CUBE_TETRAHEDRA.iter().enumerate() {
                for (cube, m) in tet_mask[p].iter_mut().enumerate() {
                    for (l, &c) in corners.iter().enumerate() {
                        *m |= ((cube >> c & 1) as u8) << l;
                    }
                }
                for mask in 0..16 {
                    let (tris, count) = &cases[p][mask];
                    pieces[p][mask].1 = *count;
                    for (t, tri) in tris.iter().enumerate().take(*count as usize) {
                        for (k, &(b, a)) in tri.iter().enumerate() {
                            // Corners along a monotone lattice path: the
                            // earlier is the edge's lower end.
                            let (lo, hi) = (b.min(a) as usize, b.max(a) as usize);
                            let (clo, chi) = (corners[lo], corners[hi]);
                            pieces[p][mask].0[t][k] = (clo, chi ^ clo);
                        }
                    }
                }
            }
            let triangles = std::array::from_fn(|cube| {
                (0..6)
                    .map(|p| pieces[p][tet_mask[p][cube] as usize].1)
                    .sum()
            });
            SweepTables {
                tet_mask,
                pieces,
                triangles,
            }
        })
    }
}

/// What the sweep shares between its workers.
struct Sweep<'a> {
    dims: [usize; 3],
    /// Per volume vertex: the corners of its cube above the cut (bit `m`
    /// for corner offset `m`; corners beyond the box copy the vertex).
    cubes: &'a [u8],
    /// `active[y + ny * z]`: false when every cube of the row has all its
    /// corners on one side of the cut (its mask is 0 or 0xff: no crossed
    /// edge, no triangle), so every pass over cubes skips the row.
    active: &'a [bool],
    /// `row_base[y + ny * z]`: id of the first contour vertex owned by the
    /// row; one more entry, the number of contour vertices.
    row_base: &'a [u32],
}

/// The edge offsets `d` (bits 1..7) of a vertex's cube whose far end lies
/// on the other side of the cut than the vertex (bit 0).
#[inline(always)]
fn crossed(cube: u8) -> u8 {
    (cube ^ (cube & 1).wrapping_neg()) & 0xfe
}

/// Every contour at `iso`, one mesh per seed's arc, sorted by arc; `None`
/// when the components and the seeds do not match one to one (then the
/// caller follows each seed instead).
pub(crate) fn all_contours_by_sweep(
    field: &ScalarField,
    seeds: &[PathSeed],
    iso: Isovalue,
) -> Option<Vec<ContourMesh>> {
    let dims = field.dims();
    if dims.iter().any(|&d| d < 2) {
        return None;
    }
    crate::with_values!(field.values(), v => sweep(v.as_slice(), field, seeds, iso))
}

/// `s` cut into consecutive pieces of the given lengths.
pub(super) fn split_lengths<T>(
    mut s: &mut [T],
    lengths: impl Iterator<Item = usize>,
) -> Vec<&mut [T]> {
    let mut out = Vec::new();
    for len in lengths {
        let (head, tail) = std::mem::take(&mut s).split_at_mut(len);
        out.push(head);
        s = tail;
    }
    out
}

/// Exclusive prefix sums of `counts`, with the total appended; `None` when
/// the total passes `limit`.
fn prefix_sums(counts: impl Iterator<Item = usize>, limit: usize) -> Option<Vec<u32>> {
    let mut out = vec![0u32];
    let mut total = 0usize;
    for c in counts {
        total += c;
        if total > limit {
            return None;
        }
        out.push(total as u32);
    }
    Some(out)
}

fn sweep<T: Scalar>(
    values: &[T],
    field: &ScalarField,
    seeds: &[PathSeed],
    iso: Isovalue,
) -> Option<Vec<ContourMesh>> {
    let [nx, ny, nz] = field.dims();
    let mut above = Vec::new();
    let mut cubes = Vec::new();
    let mut active = Vec::new();
    sides_and_cubes(
        values,
        field.dims(),
        |v, f| iso.above_value(f.to_f64(), v),
        &mut above,
        &mut cubes,
        &mut active,
        &|| false,
    );
    drop(above);

    // 1. Contour vertices, counted per row, then filled plane by plane.
    let row_counts = count_rows(&cubes, &active, nx);
    // Triangle ids and vertex ids both fit in u32 (and root/label arrays
    // stay addressable); beyond that the follower takes over.
    let row_base = prefix_sums(row_counts.into_iter(), u32::MAX as usize / 4)?;
    let n = row_base[row_base.len() - 1] as usize;
    let plane_lengths: Vec<usize> = (0..nz)
        .map(|z| (row_base[(z + 1) * ny] - row_base[z * ny]) as usize)
        .collect();
    // Fresh zeroed pages: each is first touched by a write, in parallel
    // (a read first maps the shared zero page, and the write after it then
    // costs a copy and a TLB shootdown on every core).
    let mut positions = vec![[0f32; 3]; n];
    let mut downhill = vec![[0f32; 3]; n];
    let mut on_face = vec![false; n];
    let mut normals = vec![[0f32; 3]; n];
    let lengths = || plane_lengths.iter().copied();
    split_lengths(&mut positions, lengths())
        .into_par_iter()
        .zip(split_lengths(&mut downhill, lengths()))
        .zip(split_lengths(&mut on_face, lengths()))
        .zip(split_lengths(&mut normals, lengths()))
        .enumerate()
        .for_each_init(EndGradients::default, |ends, (z, (((p, g), f), n))| {
            n.fill([0.0; 3]);
            let rows = &active[ny * z..][..ny];
            crossed_edges(values, field, &cubes, rows, iso, z, p, g, f, ends)
        });

    // 2. Triangles, counted per cube layer, then written slab by slab.
    let layer_triangles = count_layer_triangles(&cubes, &active, field.dims());
    let layer_start = prefix_sums(layer_triangles.iter().map(|t| 3 * t), u32::MAX as usize)?;
    let mut indices = vec![0u32; layer_start[nz - 1] as usize];
    let ctx = Sweep {
        dims: field.dims(),
        cubes: &cubes,
        active: &active,
        row_base: &row_base,
    };
    let layers = nz - 1;
    let slabs = layers.min(4 * rayon::current_num_threads()).max(1);
    let cut: Vec<usize> = (0..=slabs).map(|s| s * layers / slabs).collect();
    // A slab owns the planes of its layers; the last one also the top one.
    let end_plane = |s: usize| if s + 1 == slabs { nz } else { cut[s + 1] };
    let vertex_start = |z: usize| row_base[z * ny] as usize;
    let slab_vertices = (0..slabs).map(|s| vertex_start(end_plane(s)) - vertex_start(cut[s]));
    let slab_indices = (0..slabs).map(|s| (layer_start[cut[s + 1]] - layer_start[cut[s]]) as usize);
    let mut parent: Vec<u32> = (0..n as u32).into_par_iter().collect();
    split_lengths(&mut parent, slab_vertices.clone())
        .into_par_iter()
        .zip(split_lengths(&mut normals, slab_vertices))
        .zip(split_lengths(&mut indices, slab_indices))
        .enumerate()
        .for_each(|(s, ((parent, normals), indices))| {
            let mut ids = PlaneIds::default();
            let written = ctx.march_slab(
                cut[s]..cut[s + 1],
                indices,
                &layer_start,
                &|| false,
                &mut ids,
            );
            debug_assert_eq!(written, Some(indices.len()), "triangles as counted");
            // 3. Unions inside the slab: all but the last layer, whose
            // triangles reach the next slab's first plane.
            let inner = if s + 1 == slabs {
                indices.len()
            } else {
                (layer_start[cut[s + 1] - 1] - layer_start[cut[s]]) as usize
            };
            let first = vertex_start(cut[s]) as u32;
            for tri in indices[..inner].chunks_exact(3) {
                add_triangle(parent, normals, &positions, first, tri);
            }
        });
    for s in 0..slabs - 1 {
        let last = cut[s + 1] - 1;
        let range = layer_start[last] as usize..layer_start[last + 1] as usize;
        for tri in indices[range].chunks_exact(3) {
            add_triangle(&mut parent, &mut normals, &positions, 0, tri);
        }
    }
    normals
        .par_chunks_mut(1 << 14)
        .zip(downhill.par_chunks(1 << 14))
        .for_each(|(normals, downhill)| choose_normals(normals, downhill));
    drop(downhill);

    // Components: parents point down, so one ascending pass finds roots.
    let mut label = Vec::with_capacity(n);
    let mut components = 0u32;
    for i in 0..n {
        let p = parent[parent[i] as usize];
        parent[i] = p;
        if p as usize == i {
            label.push(components);
            components += 1;
        } else {
            label.push(label[p as usize]);
        }
    }

    // 4. The arc of each component, from its seed.
    if components as usize != seeds.len() {
        return None;
    }
    let mut arc_of = vec![None; components as usize];
    for seed in seeds {
        let id = edge_id(
            field,
            &ctx,
            seed.below.min(seed.above),
            seed.below.max(seed.above),
        )?;
        let c = &mut arc_of[label[id as usize] as usize];
        if c.is_some() {
            return None;
        }
        *c = Some(seed.arc);
    }
    let arcs: Vec<ArcId> = arc_of.into_iter().collect::<Option<_>>()?;
    Some(split_components(
        arcs, iso.value, &label, parent, positions, normals, indices, &on_face,
    ))
}

/// The meshes of the components: each contour's vertices in id order, its
/// triangles in sweep order. The largest is compacted in place in the
/// sweep's arrays (whose memory it then keeps), the others copied out.
#[allow(clippy::too_many_arguments)]
fn split_components(
    arcs: Vec<ArcId>,
    isovalue: f64,
    label: &[u32],
    mut local: Vec<u32>,
    mut positions: Vec<[f32; 3]>,
    mut normals: Vec<[f32; 3]>,
    mut indices: Vec<u32>,
    on_face: &[bool],
) -> Vec<ContourMesh> {
    let mut count = vec![0u32; arcs.len()];
    for &c in label {
        count[c as usize] += 1;
    }
    let largest = (0..arcs.len()).max_by_key(|&c| count[c]).unwrap_or(0) as u32;
    let mut out: Vec<ContourMesh> = arcs
        .iter()
        .map(|&a| ContourMesh::empty(a, isovalue))
        .collect();
    let mut kept = 0;
    for i in 0..label.len() {
        let c = label[i];
        out[c as usize].touches_boundary |= on_face[i];
        if c == largest {
            positions[kept] = positions[i];
            normals[kept] = normals[i];
            local[i] = kept as u32;
            kept += 1;
        } else {
            let m = &mut out[c as usize];
            local[i] = m.positions.len() as u32;
            m.positions.push(positions[i]);
            m.normals.push(normals[i]);
        }
    }
    positions.truncate(kept);
    normals.truncate(kept);
    let mut kept = 0;
    for t in 0..indices.len() / 3 {
        let tri = [0, 1, 2].map(|k| indices[3 * t + k]);
        let c = label[tri[0] as usize];
        let tri = tri.map(|v| local[v as usize]);
        if c == largest {
            indices[3 * kept..3 * kept + 3].copy_from_slice(&tri);
            kept += 1;
        } else {
            out[c as usize].indices.extend_from_slice(&tri);
        }
    }
    indices.truncate(3 * kept);
    if let Some(m) = out.get_mut(largest as usize) {
        m.positions = positions;
        m.normals = normals;
        m.indices = indices;
    }
    out.sort_unstable_by_key(|m| m.arc);
    out
}

/// The id of the contour vertex on the crossed edge from `lo` to `hi` (its
/// lower and upper end), from its row's count; `None` when the edge is not
/// a crossed mesh edge.
fn edge_id(field: &ScalarField, ctx: &Sweep, lo: u32, hi: u32) -> Option<u32> {
    let [nx, ny, _] = ctx.dims;
    let [x, y, z] = field.coords(lo);
    let [ux, uy, uz] = field.coords(hi);
    let step = [ux.checked_sub(x)?, uy.checked_sub(y)?, uz.checked_sub(z)?];
    if step.iter().any(|&s| s > 1) {
        return None;
    }
    let d = step[0] | step[1] << 1 | step[2] << 2;
    let row = nx * (y + ny * z);
    let crossed_here = crossed(ctx.cubes[lo as usize]);
    if d == 0 || crossed_here >> d & 1 == 0 {
        return None;
    }
    let before: u32 = ctx.cubes[row..lo as usize]
        .iter()
        .map(|&m| crossed(m).count_ones())
        .sum();
    let below_d = (crossed_here & ((1u8 << d) - 1)).count_ones();
    Some(ctx.row_base[y + ny * z] + before + below_d)
}

/// A vertex row whose vertices all lie below the cut.
const ALL_BELOW: u8 = 0;
/// A vertex row whose vertices all lie above the cut.
const ALL_ABOVE: u8 = 1;
/// A vertex row with vertices on both sides.
const MIXED: u8 = 2;

/// Which side of `iso` every vertex lies on (`above`, one byte each), the
/// side of every vertex row (`ALL_BELOW`, `ALL_ABOVE` or `MIXED`), the
/// cube masks (`cubes`, see [`Sweep::cubes`]) and which cube rows have a
/// crossed edge at all (`active`, see [`Sweep::active`]). The buffers are
/// resized to the field, never shrunk. Once `stop` says so the planes not
/// begun are skipped (the buffers are then partial: the caller gives up).
///
/// A cube row reads the vertex rows `{y, y + 1} × {z, z + 1}` (clamped to
/// the box, as the masks' corners are). When those four rows lie wholly on
/// one side, every mask of the row is 0 or 0xff, written without looking
/// at the corners: most of a scan's rows (air, the inside of the skull at
/// the scalp's isovalue) cost one pass of sums over `above` and a fill.
fn sides_and_cubes<T: Scalar>(
    values: &[T],
    dims: [usize; 3],
    is_above: impl Fn(u32, T) -> bool + Sync,
    above: &mut Vec<u8>,
    cubes: &mut Vec<u8>,
    active: &mut Vec<bool>,
    stop: &(dyn Fn() -> bool + Sync),
) {
    let [nx, ny, _] = dims;
    let plane = nx * ny;
    let rows = values.len() / nx;
    above.resize(values.len(), 0);
    let mut sides = vec![0u8; rows];
    above
        .par_chunks_mut(plane)
        .zip(values.par_chunks(plane))
        .zip(sides.par_chunks_mut(ny))
        .enumerate()
        .for_each(|(z, ((a, f), sides))| {
            if stop() {
                return;
            }
            for (y, side) in sides.iter_mut().enumerate() {
                let first = (plane * z + nx * y) as u32;
                let (a, f) = (&mut a[nx * y..][..nx], &f[nx * y..][..nx]);
                for (k, (a, f)) in a.iter_mut().zip(f).enumerate() {
                    *a = is_above(first + k as u32, *f) as u8;
                }
                let up: usize = a.iter().map(|&b| b as usize).sum();
                *side = match up {
                    0 => ALL_BELOW,
                    u if u == nx => ALL_ABOVE,
                    _ => MIXED,
                };
            }
        });
    cubes.resize(values.len(), 0);
    active.resize(rows, false);
    cubes
        .par_chunks_mut(plane)
        .zip(active.par_chunks_mut(ny))
        .enumerate()
        .for_each(|(z, (c, a))| {
            if !stop() {
                cube_masks(above, &sides, dims, z, c, a)
            }
        });
}

/// Crossed edges per row of vertices (see [`crossed`]); inactive rows have
/// none.
fn count_rows(cubes: &[u8], active: &[bool], nx: usize) -> Vec<usize> {
    cubes
        .par_chunks(nx)
        .zip(active.par_iter())
        .map(|(row, &a)| {
            if a {
                row.iter().map(|&m| crossed(m).count_ones() as usize).sum()
            } else {
                0
            }
        })
        .collect()
}

/// Triangles per cube layer.
fn count_layer_triangles(cubes: &[u8], active: &[bool], dims: [usize; 3]) -> Vec<usize> {
    let [nx, ny, nz] = dims;
    let tables = SweepTables::get();
    (0..nz - 1)
        .into_par_iter()
        .map(|z| {
            (0..ny - 1)
                .filter(|&y| active[y + ny * z])
                .map(|y| {
                    cubes[nx * (y + ny * z)..][..nx - 1]
                        .iter()
                        .map(|&c| tables.triangles[c as usize] as usize)
                        .sum::<usize>()
                })
                .sum()
        })
        .collect()
}

/// The cube masks of the vertices of plane `z` (see [`Sweep::cubes`]),
/// and which of its rows are active (see [`sides_and_cubes`]).
fn cube_masks(
    above: &[u8],
    sides: &[u8],
    dims: [usize; 3],
    z: usize,
    out: &mut [u8],
    active: &mut [bool],
) {
    let [nx, ny, nz] = dims;
    let plane = nx * ny;
    for y in 0..ny {
        let row = nx * (y + ny * z);
        let (y1, z1) = ((y + 1).min(ny - 1), (z + 1).min(nz - 1));
        let side = sides[y + ny * z];
        let uniform = side != MIXED
            && [y1 + ny * z, y + ny * z1, y1 + ny * z1]
                .iter()
                .all(|&r| sides[r] == side);
        active[y] = !uniform;
        if uniform {
            out[nx * y..][..nx].fill(if side == ALL_ABOVE { 0xff } else { 0 });
            continue;
        }
        // Inside the box (every corner exists): eight loads, no branch.
        let inner = if y + 1 < ny && z + 1 < nz { nx - 1 } else { 0 };
        if inner > 0 {
            let corner =
                |c: usize| &above[row + (c & 1) + nx * (c >> 1 & 1) + plane * (c >> 2)..][..inner];
            let c: [&[u8]; 8] = std::array::from_fn(corner);
            for (x, m) in out[nx * y..nx * y + inner].iter_mut().enumerate() {
                *m = c[0][x]
                    | c[1][x] << 1
                    | c[2][x] << 2
                    | c[3][x] << 3
                    | c[4][x] << 4
                    | c[5][x] << 5
                    | c[6][x] << 6
                    | c[7][x] << 7;
            }
        }
        for x in inner..nx {
            let v = x + nx * (y + ny * z);
            let inside = [x + 1 < nx, y + 1 < ny, z + 1 < nz];
            let mut m = 0u8;
            for c in 0..8 {
                let corner = if (c & 1 == 0 || inside[0])
                    && (c & 2 == 0 || inside[1])
                    && (c & 4 == 0 || inside[2])
                {
                    v + (c & 1) + nx * (c >> 1 & 1) + plane * (c >> 2 & 1)
                } else {
                    v
                };
                m |= above[corner] << c;
            }
            out[x + nx * y] = m;
        }
    }
}

/// Fills the contour vertices owned by plane `z`, in order of lower end
/// then offset: position, downhill gradient (zero where it vanishes) and
/// whether the edge lies in a face of the box (then the contour through it
/// is cut open there: the follower meets a crossed boundary face exactly
/// when its contour has such a vertex).
#[allow(clippy::too_many_arguments)]
fn crossed_edges<T: Scalar>(
    values: &[T],
    field: &ScalarField,
    cubes: &[u8],
    active: &[bool],
    iso: Isovalue,
    z: usize,
    positions: &mut [[f32; 3]],
    downhill_out: &mut [[f32; 3]],
    on_face: &mut [bool],
    ends: &mut EndGradients,
) {
    let dims = field.dims();
    let [nx, ny, _] = dims;
    let spacing = field.spacing();
    let inverse = spacing.map(f64::recip);
    ends.fit(dims);
    let mut i = 0;
    // `active` holds the plane's `ny` rows.
    for (y, &on) in active.iter().enumerate() {
        if !on {
            continue;
        }
        for x in 0..nx {
            let v = x + nx * (y + ny * z);
            let cube = cubes[v];
            let mut todo = crossed(cube);
            while todo != 0 {
                let d = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                let step = [d & 1, d >> 1 & 1, d >> 2 & 1];
                let (cv, cu) = ([x, y, z], [x + step[0], y + step[1], z + step[2]]);
                let u = v + step[0] + nx * step[1] + nx * ny * step[2];
                let ((b, cb), (a, ca)) = if cube & 1 == 1 {
                    ((u, cu), (v, cv))
                } else {
                    ((v, cv), (u, cu))
                };
                let (fb, fa) = (values[b].to_f64(), values[a].to_f64());
                // As the follower: fa > fb, or equal values with ids
                // ordered, kept inside the edge (the order's perturbation).
                let s = edge_fraction(iso.value, fb, fa);
                let p: [f32; 3] = std::array::from_fn(|k| {
                    let (pb, pa) = (cb[k] as f64, ca[k] as f64);
                    ((pb + s * (pa - pb)) * spacing[k]) as f32
                });
                positions[i] = p;
                let (gb, ga) = (ends.at(values, dims, b, cb), ends.at(values, dims, a, ca));
                downhill_out[i] = downhill_vector(gb, ga, s, inverse);
                on_face[i] = (0..3).any(|k| step[k] == 0 && (cv[k] == 0 || cv[k] + 1 == dims[k]));
                i += 1;
            }
        }
    }
    debug_assert_eq!(i, positions.len());
}

/// The box of `points` (finite, as a contour's are), eight at a time: a
/// running minimum and maximum per point is a chain of dependent steps
/// that cost a fifth of the positions' pass; lanes of a block vectorise.
fn bounds_of(points: &[[f32; 3]]) -> [[f32; 3]; 2] {
    const LANES: usize = 24;
    let flat: &[f32] = points.as_flattened();
    let (mut lo, mut hi) = ([f32::INFINITY; LANES], [f32::NEG_INFINITY; LANES]);
    let mut blocks = flat.chunks_exact(LANES);
    for b in &mut blocks {
        for k in 0..LANES {
            lo[k] = if b[k] < lo[k] { b[k] } else { lo[k] };
            hi[k] = if b[k] > hi[k] { b[k] } else { hi[k] };
        }
    }
    for (k, &x) in blocks.remainder().iter().enumerate() {
        lo[k] = lo[k].min(x);
        hi[k] = hi[k].max(x);
    }
    let mut out = NO_BOUNDS;
    for k in 0..LANES {
        out[0][k % 3] = out[0][k % 3].min(lo[k]);
        out[1][k % 3] = out[1][k % 3].max(hi[k]);
    }
    out
}

/// The box of no point: [`widen`] by anything is that thing.
const NO_BOUNDS: [[f32; 3]; 2] = [[f32::INFINITY; 3], [f32::NEG_INFINITY; 3]];

/// The least box holding both boxes.
#[inline]
fn widen([lo, hi]: [[f32; 3]; 2], [l, h]: [[f32; 3]; 2]) -> [[f32; 3]; 2] {
    [
        std::array::from_fn(|k| lo[k].min(l[k])),
        std::array::from_fn(|k| hi[k].max(h[k])),
    ]
}

impl Sweep<'_> {
    /// Marches the cube layers `layers` into `out` (their triangles, laid
    /// out by `layer_start`, offset to the first layer's), as global
    /// vertex ids; returns the number of indices written.
    fn march_slab(
        &self,
        layers: std::ops::Range<usize>,
        out: &mut [u32],
        layer_start: &[u32],
        cancel: &(dyn Fn() -> bool + Sync),
        ids: &mut PlaneIds,
    ) -> Option<usize> {
        let [nx, ny, _] = self.dims;
        let plane = nx * ny;
        let tables = SweepTables::get();
        for t in ids.iter_mut() {
            if t.len() != plane * 8 {
                *t = vec![0u32; plane * 8];
            }
        }
        let [lower, upper] = ids;
        self.fill_ids(upper, layers.start);
        let offset = layer_start[layers.start] as usize;
        let mut w = 0;
        for z in layers {
            if cancel() {
                return None;
            }
            debug_assert_eq!(w + offset, layer_start[z] as usize);
            std::mem::swap(lower, upper);
            self.fill_ids(upper, z + 1);
            for y in 0..ny - 1 {
                if !self.active[y + ny * z] {
                    continue;
                }
                for x in 0..nx - 1 {
                    let cube = self.cubes[x + nx * (y + ny * z)] as usize;
                    if cube == 0 || cube == 0xff {
                        continue;
                    }
                    let xy = x + nx * y;
                    let id = |(c, d): CornerEdge| {
                        let c = c as usize;
                        let at = (xy + (c & 1) + nx * (c >> 1 & 1)) * 8 + d as usize;
                        if c & 4 == 0 { lower[at] } else { upper[at] }
                    };
                    for p in 0..6 {
                        let mask = tables.tet_mask[p][cube] as usize;
                        let (pieces, count) = &tables.pieces[p][mask];
                        for piece in &pieces[..*count as usize] {
                            for &corner in piece {
                                out[w] = id(corner);
                                w += 1;
                            }
                        }
                    }
                }
            }
        }
        Some(w)
    }

    /// Writes the id of every contour vertex owned by plane `z` into
    /// `ids[(vertex in plane) * 8 + offset]`.
    fn fill_ids(&self, ids: &mut [u32], z: usize) {
        let [nx, ny, _] = self.dims;
        let plane = nx * ny;
        for y in 0..ny {
            let r = y + ny * z;
            let mut id = self.row_base[r];
            if id == self.row_base[r + 1] {
                continue;
            }
            let row = &self.cubes[plane * z + nx * y..][..nx];
            for (x, &cube) in row.iter().enumerate() {
                let i = x + nx * y;
                let mut todo = crossed(cube);
                while todo != 0 {
                    let d = todo.trailing_zeros() as usize;
                    todo &= todo - 1;
                    ids[i * 8 + d] = id;
                    id += 1;
                }
            }
        }
    }
}

/// Joins the triangle's vertices in the union-find over `parent` (which
/// holds the ids from `first` on; the larger root goes under the smaller)
/// and adds its area-weighted normal to theirs.
#[inline]
fn add_triangle(
    parent: &mut [u32],
    normals: &mut [[f32; 3]],
    positions: &[[f32; 3]],
    first: u32,
    tri: &[u32],
) {
    add_normal(normals, positions, first, tri);
    union_triangle(parent, first, tri);
}

/// Adds the area-weighted normal of the triangle to its vertices'
/// (`normals` holds the ids from `first` on).
#[inline]
fn add_normal(normals: &mut [[f32; 3]], positions: &[[f32; 3]], first: u32, tri: &[u32]) {
    let n = area_normal(positions, tri);
    for &i in tri {
        let s = &mut normals[(i - first) as usize];
        s[0] += n[0];
        s[1] += n[1];
        s[2] += n[2];
    }
}

/// Joins `a` and `b` in the union-find over `parent` (which holds the ids
/// from `first` on; the larger root goes under the smaller).
#[inline]
fn union(parent: &mut [u32], first: u32, a: u32, b: u32) {
    let (ra, rb) = (find(parent, first, a), find(parent, first, b));
    if ra != rb {
        parent[(ra.max(rb) - first) as usize] = ra.min(rb);
    }
}

/// Joins the triangle's vertices in the union-find over `parent` (which
/// holds the ids from `first` on; the larger root goes under the smaller).
#[inline]
fn union_triangle(parent: &mut [u32], first: u32, tri: &[u32]) {
    union(parent, first, tri[0], tri[1]);
    union(parent, first, tri[0], tri[2]);
}

/// The root of `x`, halving the path (`parent` holds ids from `first` on).
#[inline]
fn find(parent: &mut [u32], first: u32, mut x: u32) -> u32 {
    loop {
        let p = parent[(x - first) as usize];
        if p == x {
            return x;
        }
        let g = parent[(p - first) as usize];
        parent[(x - first) as usize] = g;
        x = g;
    }
}

/// The field's gradient at the grid vertices of two consecutive planes,
/// each computed once ([`end_gradient`]): a contour vertex interpolates
/// the gradients of its edge's two ends, and a grid vertex beside the
/// isosurface is the end of four or five crossed edges. A worker keeps one
/// from plane to plane (plane `z + 1`'s ends are the next plane's lower
/// ones); a slot remembers which plane filled it, so nothing is cleared.
#[derive(Default)]
pub(crate) struct EndGradients {
    /// The plane (plus one) whose gradient `slot` holds; 0: none.
    plane: Vec<u32>,
    gradient: Vec<[f64; 3]>,
    nx: usize,
    area: usize,
}

impl EndGradients {
    /// Sized for planes of `dims`.
    fn fit(&mut self, dims: [usize; 3]) {
        let area = dims[0] * dims[1];
        if self.area != area || self.nx != dims[0] {
            self.plane = vec![0; 2 * area];
            self.gradient = vec![[0.0; 3]; 2 * area];
            (self.nx, self.area) = (dims[0], area);
        }
    }

    /// The gradient at grid vertex `v` (coordinates `c`), as
    /// [`end_gradient`] gives it.
    #[inline]
    fn at<T: Scalar>(
        &mut self,
        values: &[T],
        dims: [usize; 3],
        v: usize,
        c: [usize; 3],
    ) -> [f64; 3] {
        let slot = c[0] + self.nx * c[1] + self.area * (c[2] & 1);
        let tag = c[2] as u32 + 1;
        if self.plane[slot] != tag {
            self.plane[slot] = tag;
            self.gradient[slot] = end_gradient(values, dims, (v, c));
        }
        self.gradient[slot]
    }
}

/// Tables [`contour_by_sweep`] keeps from one call to the next: a fresh
/// page costs as much as the work done on it, and a drag asks for the
/// same sizes again and again. Two bytes per volume vertex (side of the
/// contour, cube masks), sized by the largest call so far.
#[derive(Default)]
pub(crate) struct SweepScratch {
    above: Vec<u8>,
    cubes: Vec<u8>,
    active: Vec<bool>,
    /// Per slab, its two planes' vertex-id tables.
    plane_ids: Vec<PlaneIds>,
    /// Per contour vertex, the downhill gradient and whether it lies on a
    /// face of the box (longer than needed after a larger contour).
    downhill: Vec<[f32; 3]>,
    on_face: Vec<bool>,
    /// Per run of planes, its gradient table.
    ends: Vec<EndGradients>,
}

/// The dense vertex-id tables of a cube layer's lower and upper planes
/// (see [`Sweep::fill_ids`]).
type PlaneIds = [Vec<u32>; 2];

/// The single contour through `seed` at `iso` by the parallel sweep, told
/// apart from the other contours at `iso` by the tree: every vertex gets
/// its side of this contour ([`CutSides`]) in place of its side of the
/// cut, so the crossed edges and tetrahedra marched are this contour's
/// alone (step 3 of the module doc is not needed), and positions,
/// gradients and normals are computed for its own vertices only. The same
/// triangles as following the seed (the same case tables, numbering and
/// interpolation), its vertices in edge order, its triangles in sweep
/// order. `Ok(None)` when the seed's edge is not crossed or the contour
/// does not fit the sweep's `u32` ids (the caller then follows the seed);
/// `Err` as soon as `cancel` answers true (checked between phases and
/// before every cube layer of every slab). The mesh is written into
/// `spare`'s arrays where they are large enough.
#[allow(clippy::too_many_arguments)]
pub(crate) fn contour_by_sweep(
    field: &ScalarField,
    tree: &ContourTree,
    seed: &PathSeed,
    iso: Isovalue,
    scratch: &mut SweepScratch,
    spare: ContourMesh,
    cancel: &(dyn Fn() -> bool + Sync),
) -> Result<Option<ContourMesh>, Cancelled> {
    let dims = field.dims();
    if dims.iter().any(|&d| d < 2) || tree.num_vertices() != field.len() {
        return Ok(None);
    }
    let sides = CutSides::new(tree, seed.arc);
    crate::with_values!(field.values(), v => sweep_one(v.as_slice(), field, tree, &sides, seed, iso, scratch, spare, cancel))
}

#[allow(clippy::too_many_arguments)]
fn sweep_one<T: Scalar>(
    values: &[T],
    field: &ScalarField,
    tree: &ContourTree,
    sides: &CutSides,
    seed: &PathSeed,
    iso: Isovalue,
    scratch: &mut SweepScratch,
    spare: ContourMesh,
    cancel: &(dyn Fn() -> bool + Sync),
) -> Result<Option<ContourMesh>, Cancelled> {
    let check = || if cancel() { Err(Cancelled) } else { Ok(()) };
    let dims = field.dims();
    let [nx, ny, nz] = dims;
    let SweepScratch {
        above,
        cubes,
        active,
        plane_ids,
        downhill,
        on_face,
        ends,
    } = scratch;
    let side = |v: u32, f: T| sides.is_upper(tree, v, || iso.above_value(f.to_f64(), v));
    sides_and_cubes(values, dims, side, above, cubes, active, cancel);
    let active: &[bool] = active;
    check()?;

    // 1. Crossed edges numbered by rows (see the module doc): this
    // contour's vertices.
    let row_counts = count_rows(cubes, active, nx);
    let Some(row_base) = prefix_sums(row_counts.into_iter(), u32::MAX as usize / 4) else {
        return Ok(None);
    };
    let n = row_base[row_base.len() - 1] as usize;
    let ctx = Sweep {
        dims,
        cubes,
        active,
        row_base: &row_base,
    };
    if edge_id(
        field,
        &ctx,
        seed.below.min(seed.above),
        seed.below.max(seed.above),
    )
    .is_none()
    {
        return Ok(None);
    }
    let vertex_start = |z: usize| row_base[z * ny] as usize;
    let plane_lengths: Vec<usize> = (0..nz)
        .map(|z| vertex_start(z + 1) - vertex_start(z))
        .collect();

    // 2. Its triangles, slab by slab.
    let layer_triangles = count_layer_triangles(cubes, active, dims);
    let Some(layer_start) = prefix_sums(layer_triangles.iter().map(|t| 3 * t), u32::MAX as usize)
    else {
        return Ok(None);
    };
    // Every index and position is written below.
    let mut indices = crate::pages::reused(spare.indices, layer_start[nz - 1] as usize, 0u32);
    let layers = nz - 1;
    let slabs = layers.min(4 * rayon::current_num_threads()).max(1);
    let cut: Vec<usize> = (0..=slabs).map(|s| s * layers / slabs).collect();
    let end_plane = |s: usize| if s + 1 == slabs { nz } else { cut[s + 1] };
    let slab_indices: Vec<usize> = (0..slabs)
        .map(|s| (layer_start[cut[s + 1]] - layer_start[cut[s]]) as usize)
        .collect();
    plane_ids.resize_with(slabs, PlaneIds::default);
    let marched: Vec<bool> = split_lengths(&mut indices, slab_indices.iter().copied())
        .into_par_iter()
        .zip(plane_ids.par_iter_mut())
        .enumerate()
        .map(|(s, (indices, ids))| {
            let layers = cut[s]..cut[s + 1];
            let Some(written) = ctx.march_slab(layers, indices, &layer_start, cancel, ids) else {
                return false;
            };
            debug_assert_eq!(written, indices.len(), "triangles as counted");
            true
        })
        .collect();
    if marched.contains(&false) {
        return Err(Cancelled);
    }
    check()?;

    // Positions, gradients and face flags, plane by plane.
    let mut positions = crate::pages::reused(spare.positions, n, [0f32; 3]);
    // Every entry is written below: no need to clear them.
    if downhill.len() < n {
        // With room for the next steps of a drag (see `pages::headroom`).
        let grown = crate::pages::headroom(downhill.len(), n);
        *downhill = crate::pages::filled(grown, [0f32; 3]);
        *on_face = crate::pages::filled(grown, false);
    }
    let (downhill, on_face) = (&mut downhill[..n], &mut on_face[..n]);
    // Runs of consecutive planes, each with its own kept gradient table (a
    // plane's upper ends are the next plane's lower ones; a table made per
    // task was 2 MB of fresh pages each time on colin27).
    let runs = (4 * rayon::current_num_threads()).min(nz).max(1);
    let run_start: Vec<usize> = (0..=runs).map(|r| r * nz / runs).collect();
    let run_lengths =
        || (0..runs).map(|r| vertex_start(run_start[r + 1]) - vertex_start(run_start[r]));
    ends.resize_with(runs, EndGradients::default);
    let bounds = split_lengths(&mut positions, run_lengths())
        .into_par_iter()
        .zip(split_lengths(&mut *downhill, run_lengths()))
        .zip(split_lengths(&mut *on_face, run_lengths()))
        .zip(ends.par_iter_mut())
        .enumerate()
        .map(|(r, (((p, g), f), ends))| {
            let planes = run_start[r]..run_start[r + 1];
            let lengths = || plane_lengths[planes.clone()].iter().copied();
            let (p, g, f) = (
                split_lengths(p, lengths()),
                split_lengths(g, lengths()),
                split_lengths(f, lengths()),
            );
            let mut bounds = NO_BOUNDS;
            for (z, ((p, g), f)) in planes.clone().zip(p.into_iter().zip(g).zip(f)) {
                if cancel() {
                    break;
                }
                let rows = &active[ny * z..][..ny];
                crossed_edges(values, field, cubes, rows, iso, z, p, g, f, ends);
                // While the plane's positions are in cache.
                bounds = widen(bounds, bounds_of(p));
            }
            bounds
        })
        .reduce(|| NO_BOUNDS, widen);
    check()?;

    // Area-weighted normals: a slab's inner layers touch its own vertices
    // only (in parallel), its last layer the next slab's too (after).
    let mut normals = crate::pages::refilled(spare.normals, n, [0f32; 3]);
    // Where a slab's last layer starts: that layer reaches the next slab's
    // first plane.
    let inner_end = |s: usize| {
        if s + 1 == slabs {
            layer_start[cut[s + 1]] as usize
        } else {
            layer_start[cut[s + 1] - 1] as usize
        }
    };
    let slab_vertices = (0..slabs).map(|s| vertex_start(end_plane(s)) - vertex_start(cut[s]));
    split_lengths(&mut normals, slab_vertices)
        .into_par_iter()
        .enumerate()
        .for_each(|(s, normals)| {
            let first = vertex_start(cut[s]) as u32;
            let start = layer_start[cut[s]] as usize;
            for tri in indices[start..inner_end(s)].chunks_exact(3) {
                add_normal(normals, &positions, first, tri);
            }
        });
    for s in 0..slabs - 1 {
        let end = layer_start[cut[s + 1]] as usize;
        for tri in indices[inner_end(s)..end].chunks_exact(3) {
            add_normal(&mut normals, &positions, 0, tri);
        }
    }
    normals
        .par_chunks_mut(1 << 14)
        .zip(downhill.par_chunks(1 << 14))
        .for_each(|(normals, downhill)| choose_normals(normals, downhill));
    let touches_boundary = on_face.par_iter().any(|&f| f);
    // A cube layer's triangles have their corners on the edges owned by
    // its two planes.
    let mut bands = spare.bands;
    bands.clear();
    bands.extend((0..layers).filter_map(|z| {
        let corners = layer_start[z]..layer_start[z + 1];
        let vertices = vertex_start(z) as u32..vertex_start(z + 2) as u32;
        (!corners.is_empty()).then_some(TriangleBand { corners, vertices })
    }));
    Ok(Some(ContourMesh {
        arc: seed.arc,
        isovalue: iso.value,
        positions,
        normals,
        indices,
        touches_boundary,
        // The triangles wind counter-clockwise seen from below; a closed
        // contour's outside is the side of the box's corner.
        ccw_outward: Some(above[0] == 0),
        bounds: Some(bounds),
        bands,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::ContourFollower;
    use crate::contour::global::spanning_arcs;
    use crate::contour::seed::PathSeeds;
    use crate::field::Values;
    use crate::progress::Progress;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// The whole isosurface by one sweep tells its contours apart
        /// itself (its components match the spanning arcs one to one, so
        /// no caller falls back to following), each the follower's:
        /// random 8-bit grids with many ties, cut into slabs.
        #[test]
        fn the_sweep_tells_every_contour_apart(
            field in (2usize..9, 2usize..9, 2usize..12).prop_flat_map(|(x, y, z)| {
                proptest::collection::vec(0u8..5, x * y * z).prop_map(move |v| {
                    ScalarField::new([x, y, z], Values::U8(v)).expect("valid")
                })
            }),
            h in 0u8..9,
        ) {
            let tree = ContourTree::from_field(&field, &Progress::new()).expect("built").0;
            let iso = Isovalue::new(h as f64 / 2.0);
            let path_seeds = PathSeeds::new();
            let seeds: Vec<PathSeed> = spanning_arcs(&tree, &field, iso)
                .into_iter()
                .filter_map(|arc| path_seeds.seed(&tree, &field, arc, iso))
                .collect();
            let swept = all_contours_by_sweep(&field, &seeds, iso);
            prop_assert!(swept.is_some(), "the components match the seeds");
            let swept = swept.unwrap_or_default();
            prop_assert_eq!(swept.len(), seeds.len());
            let mut follower = ContourFollower::new(&field);
            for seed in &seeds {
                let mesh = swept.iter().find(|m| m.arc == seed.arc);
                prop_assert!(mesh.is_some(), "a mesh per arc");
                let want = follower.follow(seed, iso);
                let got = mesh.map(ContourMesh::triangle_soup).unwrap_or_default();
                prop_assert_eq!(got, want.triangle_soup());
            }
        }
    }
}
