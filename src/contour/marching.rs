//! The marching-tetrahedra primitives the contour extractors share: the
//! tables of the six Freudenthal tetrahedra of a cube (cases, face
//! neighbours), the id hasher of their tables, the cancellation answer, and
//! the vertex geometry (where a contour crosses an edge, downhill
//! gradient, area-weighted face normals, vertex normals). The follower ([`super::follow`]), the parallel sweep
//! ([`super::sweep`]) and the tests' oracles ([`super::oracle`]) all build
//! on these, so none of them imports another for them.

use crate::field::Scalar;
use crate::mesh::CUBE_TETRAHEDRA;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::OnceLock;

/// How far inside a crossed mesh edge its contour vertex is kept, as a
/// fraction of the edge (see [`edge_fraction`]).
pub const EDGE_MARGIN: f64 = 1.0 / 256.0;

/// Where the level set of value `h` crosses a mesh edge, as the fraction
/// of the way from its end below (value `fb`) to its end above (`fa`),
/// kept within `[EDGE_MARGIN, 1 - EDGE_MARGIN]`; ends of equal value
/// (ordered by their ids, the vertex order's perturbation) give the
/// midpoint.
///
/// **Why a margin.** An isovalue is a cut in the vertex order
/// ([`crate::field::Isovalue`]): a vertex of value exactly `h` lies
/// strictly on one side, as if the field there were `h ± δ` for a
/// vanishing `δ` (simulation of simplicity). Interpolating the unperturbed
/// values would put the contour vertex of every crossed edge from such a
/// vertex at the vertex itself: several mesh vertices at one place and
/// triangles of no area, which readers drop or merge (VTK's STL reader,
/// trimesh's vertex merge) and which split or pinch the surface they see.
/// Kept strictly inside its edge, each contour vertex realises the
/// perturbation geometrically: the surface is the level set of a field
/// perturbed by less than the margin, with the very same triangles.
///
/// *Claim:* any choice of points strictly inside the crossed edges gives
/// an embedded surface with the same combinatorics, hence exactly the
/// topology the contour tree predicts, no triangle of zero area and no
/// two vertices at one place. *Sketch:* a marching-tetrahedra piece is a
/// triangle or a quadrilateral whose corners lie on edges of its
/// tetrahedron and whose sides lie on its faces; neighbours share those
/// sides, so pieces meet only along them. A triangle's three edges share
/// an end, whose three edge directions are independent, so its corners
/// are never collinear; each half of a quadrilateral has two corners on
/// one face and the third on an edge leaving that face's plane at a
/// corner the point does not reach. Distinct mesh edges share at most an
/// end, so points inside them are distinct.
///
/// The cost is a vertex moved by at most `EDGE_MARGIN` of its edge (1/256
/// of a voxel's diagonal at most), and vertices that would coincide are
/// then that far apart, several float32 steps for coordinates below
/// about 2^13 voxel sizes.
#[inline]
pub fn edge_fraction(h: f64, fb: f64, fa: f64) -> f64 {
    if fa != fb {
        ((h - fb) / (fa - fb)).clamp(EDGE_MARGIN, 1.0 - EDGE_MARGIN)
    } else {
        0.5
    }
}

/// Multiply-xorshift hasher for 64-bit ids (tetrahedra, edges).
#[derive(Clone, Copy, Debug, Default)]
pub struct IdHasher(u64);

impl Hasher for IdHasher {
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    #[inline]
    fn write_u64(&mut self, x: u64) {
        let h = (x ^ self.0).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        self.0 = h ^ (h >> 29);
    }
}

/// Hash-builder of [`IdHasher`].
pub type IdBuildHasher = BuildHasherDefault<IdHasher>;

/// A triangle of a marching-tetrahedra case: three crossed edges of the
/// tetrahedron, each as (local index below, local index above).
pub(crate) type CaseTriangle = [(u8, u8); 3];

/// Tables of the six tetrahedra of a cube.
pub(crate) struct TetTables {
    /// Neighbour across the face opposite local vertex k: cube offset and
    /// the neighbour's permutation.
    pub(crate) neighbour: [[([i64; 3], u8); 4]; 6],
    /// Triangles for (permutation, bit mask of the local vertices above),
    /// wound counter-clockwise seen from below.
    pub(crate) cases: [[([CaseTriangle; 2], u8); 16]; 6],
}

/// Corner of a cube (bit mask) as integer coordinates.
pub(super) fn corner(m: u8) -> [i64; 3] {
    [(m & 1) as i64, (m >> 1 & 1) as i64, (m >> 2 & 1) as i64]
}

impl TetTables {
    pub(crate) fn get() -> &'static TetTables {
        static T: OnceLock<TetTables> = OnceLock::new();
        T.get_or_init(TetTables::new)
    }

    fn new() -> Self {
        let axis = |bit: u8| bit.trailing_zeros() as usize;
        let perm: [[usize; 3]; 6] =
            CUBE_TETRAHEDRA.map(|t| [axis(t[1]), axis(t[2] ^ t[1]), axis(t[3] ^ t[2])]);
        let find = |p: [usize; 3]| {
            perm.iter()
                .position(|q| *q == p)
                .map(|i| i as u8)
                .unwrap_or(0)
        };
        let neighbour = perm.map(|[i, j, k]| {
            let mut e = [[0i64; 3]; 3];
            e[0][i] = 1;
            e[1][j] = 1;
            e[2][k] = 1;
            [
                (e[0], find([j, k, i])),
                ([0; 3], find([j, i, k])),
                ([0; 3], find([i, k, j])),
                (e[2].map(|c| -c), find([k, i, j])),
            ]
        });
        let mut cases = [[([[(0u8, 0u8); 3]; 2], 0u8); 16]; 6];
        for p in 0..6 {
            let pos = CUBE_TETRAHEDRA[p].map(corner);
            for mask in 1u8..15 {
                let above: Vec<u8> = (0..4).filter(|&l| mask >> l & 1 == 1).collect();
                let below: Vec<u8> = (0..4).filter(|&l| mask >> l & 1 == 0).collect();
                // Crossed edges in cyclic order around the piece.
                let cycle: Vec<(u8, u8)> = match (below.len(), above.len()) {
                    (1, 3) => above.iter().map(|&a| (below[0], a)).collect(),
                    (3, 1) => below.iter().map(|&b| (b, above[0])).collect(),
                    _ => vec![
                        (below[0], above[0]),
                        (below[1], above[0]),
                        (below[1], above[1]),
                        (below[0], above[1]),
                    ],
                };
                // Orient with edge midpoints (doubled, exact): the piece's
                // normal must point to the below side. Positive diagonal
                // scaling (spacing) and sliding the points along their edges
                // (interpolation) keep the sign.
                let mid = |(b, a): (u8, u8)| {
                    let (pb, pa) = (pos[b as usize], pos[a as usize]);
                    [pb[0] + pa[0], pb[1] + pa[1], pb[2] + pa[2]]
                };
                let m: Vec<[i64; 3]> = cycle.iter().map(|&e| mid(e)).collect();
                let sub = |a: [i64; 3], b: [i64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
                let (u, v) = (sub(m[1], m[0]), sub(m[2], m[0]));
                let n = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                let centroid = |s: &[u8]| {
                    s.iter()
                        .fold([0i64; 3], |c, &l| {
                            let q = pos[l as usize];
                            [c[0] + 4 * q[0], c[1] + 4 * q[1], c[2] + 4 * q[2]]
                        })
                        .map(|c| c / s.len() as i64)
                };
                let d = sub(centroid(&below), centroid(&above));
                let mut cycle = cycle;
                if n[0] * d[0] + n[1] * d[1] + n[2] * d[2] < 0 {
                    cycle.reverse();
                }
                let mut tris = [[(0u8, 0u8); 3]; 2];
                tris[0] = [cycle[0], cycle[1], cycle[2]];
                let count = if cycle.len() == 4 {
                    tris[1] = [cycle[0], cycle[2], cycle[3]];
                    2
                } else {
                    1
                };
                cases[p][mask as usize] = (tris, count);
            }
        }
        Self { neighbour, cases }
    }
}

/// Why an extraction stopped before its end: the caller's cancel check
/// answered true (a newer request superseded it). Nothing of the partial
/// contour is returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the contour extraction was cancelled")]
pub struct Cancelled;

/// Unit vertex normals from the field's gradient (central differences,
/// one-sided on the box's faces), interpolated along each vertex's mesh
/// edge `(below, above, s)` and pointing downhill. Where the gradient
/// vanishes (plateaus of quantised scans, exactly where `h = f(v)`
/// extraction lands) or disagrees with the triangles' winding (the
/// central-difference gradient is not the gradient of the piecewise-linear
/// interpolant the triangles come from), the area-weighted triangle normal
/// stands in, so shading never flips a vertex inside out ([`choose_normal`]).
pub fn gradient_normals<T: Scalar>(
    values: &[T],
    dims: [usize; 3],
    spacing: [f64; 3],
    vertex_edges: &[(u32, u32, f32)],
    positions: &[[f32; 3]],
    indices: &[u32],
) -> Vec<[f32; 3]> {
    let mut normals = vec![[0f32; 3]; positions.len()];
    add_area_normals(&mut normals, positions, indices);
    let coords = |v: u32| {
        let v = v as usize;
        (
            v,
            [v % dims[0], v / dims[0] % dims[1], v / (dims[0] * dims[1])],
        )
    };
    for (n, &(b, a, s)) in normals.iter_mut().zip(vertex_edges) {
        let g = downhill(values, dims, spacing, coords(b), coords(a), s as f64);
        *n = choose_normal(*n, g);
    }
    normals
}

/// The [`downhill_vector`] at the contour vertex a fraction `s` from
/// `below` to `above` (each a vertex id with its coordinates): the field's
/// gradients at the two ends (central differences, one-sided on the box's
/// faces), interpolated and negated.
#[inline]
pub(crate) fn downhill<T: Scalar>(
    values: &[T],
    dims: [usize; 3],
    spacing: [f64; 3],
    below: (usize, [usize; 3]),
    above: (usize, [usize; 3]),
    s: f64,
) -> [f32; 3] {
    let (gb, ga) = (
        end_gradient(values, dims, below),
        end_gradient(values, dims, above),
    );
    // Loop-invariant where this is inlined into a loop over vertices.
    let inverse = spacing.map(f64::recip);
    downhill_vector(gb, ga, s, inverse)
}

/// The field's gradient at vertex `v` (id and coordinates) per index step:
/// central differences, one-sided on the box's faces (the spacing is
/// applied after the interpolation, by [`downhill_vector`]).
#[inline]
pub(crate) fn end_gradient<T: Scalar>(
    values: &[T],
    dims: [usize; 3],
    (v, c): (usize, [usize; 3]),
) -> [f64; 3] {
    let stride = [1, dims[0], dims[0] * dims[1]];
    std::array::from_fn(|k| {
        if c[k] > 0 && c[k] + 1 < dims[k] {
            0.5 * (values[v + stride[k]].to_f64() - values[v - stride[k]].to_f64())
        } else if c[k] > 0 {
            values[v].to_f64() - values[v - stride[k]].to_f64()
        } else if c[k] + 1 < dims[k] {
            values[v + stride[k]].to_f64() - values[v].to_f64()
        } else {
            0.0
        }
    })
}

/// The downhill gradient a fraction `s` of the way between two
/// [`end_gradient`]s, given the reciprocal spacing, *not* normalised (the
/// length is taken once per vertex by [`choose_normals`], in bulk, where
/// it costs a tenth of a square root and a division per crossed edge in
/// double precision); zero where it is not finite in `f32` (an underflow
/// reads as a vanished gradient: the triangles' normal then stands in).
#[inline]
pub(crate) fn downhill_vector(gb: [f64; 3], ga: [f64; 3], s: f64, inverse: [f64; 3]) -> [f32; 3] {
    let g: [f32; 3] = std::array::from_fn(|k| (-(gb[k] + s * (ga[k] - gb[k])) * inverse[k]) as f32);
    if g.iter().all(|x| x.is_finite()) {
        g
    } else {
        [0.0; 3]
    }
}

/// The unit vertex normal from its area-weighted sum `n` (as
/// [`add_area_normals`] leaves it) and its [`downhill_vector`] `g`: the
/// unit gradient where it agrees with the triangles' winding (a positive
/// dot product with the sum), else the unit sum (+z where the sum
/// vanishes). So shading follows the field's smooth gradient but never
/// flips a vertex inside out where the central differences disagree with
/// the piecewise-linear interpolant the triangles come from.
#[inline]
pub(crate) fn choose_normal(n: [f32; 3], g: [f32; 3]) -> [f32; 3] {
    let (chosen, plain) = plain_choice(n, g);
    if plain {
        return chosen;
    }
    let a = unit(n).unwrap_or([0.0, 0.0, 1.0]);
    match unit(g) {
        Some(u) if dot(u, a) > 0.0 => u,
        _ => a,
    }
}

/// [`choose_normal`] for every vertex, in place of its area-weighted sum:
/// eight vertices at a time without a branch (so the square roots and
/// divisions vectorise), the rare block holding a degenerate one by the
/// vertex.
pub(crate) fn choose_normals(normals: &mut [[f32; 3]], downhill: &[[f32; 3]]) {
    const LANES: usize = 8;
    let mut blocks = normals.chunks_exact_mut(LANES);
    let mut gradients = downhill.chunks_exact(LANES);
    for (n, g) in (&mut blocks).zip(&mut gradients) {
        let mut out = [[0f32; 3]; LANES];
        let mut plain = true;
        for k in 0..LANES {
            let (chosen, p) = plain_choice(n[k], g[k]);
            out[k] = chosen;
            plain &= p;
        }
        if plain {
            n.copy_from_slice(&out);
        } else {
            for (n, g) in n.iter_mut().zip(g) {
                *n = choose_normal(*n, *g);
            }
        }
    }
    for (n, g) in blocks
        .into_remainder()
        .iter_mut()
        .zip(gradients.remainder())
    {
        *n = choose_normal(*n, *g);
    }
}

/// [`choose_normal`] without a branch, for every vertex but those of
/// degenerate triangles or extreme gradients; false for those (whose
/// squared lengths are zero, tiny or huge), and the first value is then
/// meaningless.
#[inline(always)]
fn plain_choice(n: [f32; 3], g: [f32; 3]) -> ([f32; 3], bool) {
    let (ln, lg) = (dot(n, n), dot(g, g));
    // No gradient at all, not one whose squared length underflows to zero
    // (a gradient of 1e-23 still has a direction, which the careful path
    // takes).
    let vanished = (g[0] == 0.0) & (g[1] == 0.0) & (g[2] == 0.0);
    let plain = plain_length(ln) & (vanished | plain_length(lg));
    let take = (lg != 0.0) & (dot(n, g) > 0.0);
    let (v, l) = if take { (g, lg) } else { (n, ln) };
    let r = l.sqrt().recip();
    (v.map(|x| x * r), plain)
}

#[inline(always)]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A squared length whose square root and reciprocal are taken without
/// overflow or precision lost to underflow.
#[inline(always)]
fn plain_length(l2: f32) -> bool {
    (1e-30..1e30).contains(&l2)
}

/// `v` scaled to unit length; None when it is zero or not finite. The
/// squared length is taken in `f32` where that neither overflows nor
/// loses precision to underflow, else after scaling by the largest
/// component.
#[inline]
fn unit(v: [f32; 3]) -> Option<[f32; 3]> {
    let l2 = dot(v, v);
    if plain_length(l2) {
        let r = l2.sqrt().recip();
        return Some(v.map(|x| x * r));
    }
    let m = v[0].abs().max(v[1].abs()).max(v[2].abs());
    if !(m > 0.0 && m.is_finite()) {
        return None;
    }
    let w = v.map(|x| x / m);
    let r = dot(w, w).sqrt().recip();
    Some(w.map(|x| x * r))
}

/// Unit vertex normals as area-weighted sums of the triangle normals (a
/// vertex whose triangles all have zero area, or that no triangle uses,
/// gets +z; triangles with a corner out of range or a non-finite normal
/// are skipped). The one definition: the renderer's `compute_normals` is
/// this function, and the sweep adds the same [`area_normal`]s.
pub fn vertex_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut acc = vec![[0f32; 3]; positions.len()];
    add_area_normals(&mut acc, positions, indices);
    for n in &mut acc {
        *n = unit(*n).unwrap_or([0.0, 0.0, 1.0]);
    }
    acc
}

/// Adds each triangle's [`area_normal`] to its three vertices' sums in
/// `acc` (triangles with a corner out of range or a non-finite normal are
/// skipped).
pub(crate) fn add_area_normals(acc: &mut [[f32; 3]], positions: &[[f32; 3]], indices: &[u32]) {
    for tri in indices.chunks_exact(3) {
        if tri.iter().any(|&i| i as usize >= positions.len()) {
            continue;
        }
        let n = area_normal(positions, tri);
        if !n.iter().all(|c| c.is_finite()) {
            continue;
        }
        for &i in tri {
            let s = &mut acc[i as usize];
            s[0] += n[0];
            s[1] += n[1];
            s[2] += n[2];
        }
    }
}

/// Twice the area times the unit normal of triangle `tri` (counter-
/// clockwise), the weight of a face in an area-weighted vertex normal.
#[inline]
pub(crate) fn area_normal(positions: &[[f32; 3]], tri: &[u32]) -> [f32; 3] {
    let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| positions[i as usize]);
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A component from every range a normal or gradient can take: zero,
    /// tiny, plain, huge, either sign.
    fn component() -> impl Strategy<Value = f32> {
        prop_oneof![
            Just(0.0f32),
            -1e3f32..1e3,
            (-1.0f32..1.0).prop_map(|x| x * 1e-20),
            (-1.0f32..1.0).prop_map(|x| x * 1e25),
        ]
    }

    fn vector() -> impl Strategy<Value = [f32; 3]> {
        [component(), component(), component()]
    }

    /// Mostly plain pairs, so that most blocks of eight take the
    /// vectorised path, and some from every range.
    fn pair() -> impl Strategy<Value = ([f32; 3], [f32; 3])> {
        let plain = || [-1e3f32..1e3, -1e3f32..1e3, -1e3f32..1e3];
        prop_oneof![40 => (plain(), plain()), 1 => (vector(), vector())]
    }

    /// A gradient whose squared length underflows in `f32` still has a
    /// direction: it is taken where it agrees with the sum (the case a
    /// proptest found), by the vertex and in blocks of eight.
    #[test]
    fn a_tiny_gradient_keeps_its_direction() {
        let (n, g) = (
            [-327.39874f32, -207.86232, 0.0],
            [-5.8785055e-24f32, 0.0, 0.0],
        );
        assert_eq!(choose_normal(n, g), [-1.0, 0.0, 0.0]);
        let mut blocked = vec![n; 8];
        choose_normals(&mut blocked, &[g; 8]);
        assert!(blocked.iter().all(|&b| b == [-1.0, 0.0, 0.0]));
    }

    proptest! {
        /// The blocked pass gives every vertex exactly the scalar rule's
        /// bits, and the rule is the one its doc states, checked in double
        /// precision: a unit vector, the gradient's direction where its
        /// dot product with the sum is clearly positive, the sum's where
        /// clearly not.
        #[test]
        fn normals_chosen_in_blocks_are_the_rule(
            pairs in proptest::collection::vec(pair(), 0..40)
        ) {
            let (sums, gradients): (Vec<_>, Vec<_>) = pairs.iter().copied().unzip();
            let mut blocked = sums.clone();
            choose_normals(&mut blocked, &gradients);
            for ((&n, &g), &b) in sums.iter().zip(&gradients).zip(&blocked) {
                let one = choose_normal(n, g);
                prop_assert_eq!(one.map(f32::to_bits), b.map(f32::to_bits));
                let wide = |v: [f32; 3]| v.map(f64::from);
                let len = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                prop_assert!((len(wide(b)) - 1.0).abs() < 1e-5, "unit: {:?}", b);
                let (wn, wg) = (wide(n), wide(g));
                let (ln, lg) = (len(wn), len(wg));
                let a = if ln > 0.0 { wn.map(|x| x / ln) } else { [0.0, 0.0, 1.0] };
                let same = |v: [f64; 3]| (0..3).all(|k| (v[k] - b[k] as f64).abs() < 1e-5);
                if lg > 0.0 {
                    let u = wg.map(|x| x / lg);
                    let d = u[0] * a[0] + u[1] * a[1] + u[2] * a[2];
                    if d > 1e-4 {
                        prop_assert!(same(u), "the gradient {:?} for {:?}, got {:?}", g, n, b);
                    } else if d < -1e-4 {
                        prop_assert!(same(a), "the sum {:?} against {:?}, got {:?}", n, g, b);
                    }
                } else {
                    prop_assert!(same(a), "the sum {:?} without a gradient, got {:?}", n, b);
                }
            }
        }
    }
}
