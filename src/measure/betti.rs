//! Betti numbers of the contours of every superarc (Pascucci &
//! Cole-McLaughlin, "Parallel computation of the topology of level sets",
//! §4).
//!
//! **LUStars.** Passing a vertex `v` upwards changes the level set only
//! inside v's star: the simplices of the lower star (v and vertices below
//! it) stop being crossed, those of the upper star start. Each crossed
//! simplex of dimension k gives one (k-1)-cell of the level set, so the
//! Euler characteristic χ of the level set jumps by `LS(v) - US(v)` where
//! `LS = 1 - #lower edges + #lower triangles - #lower tetrahedra` and `US`
//! alike; equivalently χ(upper link) - χ(lower link). The Freudenthal
//! triangulation is a flag complex (a set of vertices is a simplex iff they
//! are pairwise joined), so χ of any part of a vertex's link is read from
//! one table over the bit masks of its 14 neighbours. Boundary edges of the
//! level set (crossed boundary triangles of the box) jump by the boundary
//! triangles whose lowest vertex is `v`, minus those whose highest is `v`.
//!
//! **The linear pass.** At a supernode the χ of the contours on the arcs
//! below plus LS equals the χ on the arcs above plus US (paper, eq. 1);
//! along a superarc χ changes by LS - US at each regular vertex. Peeling the
//! tree from its leaves (paper, `AugmentedContourTree`) solves these
//! equations for the χ at the bottom of every superarc; a walk up each arc
//! gives the rest.
//!
//! **Sub-arcs.** A superarc can change genus (or open and close against the
//! box) at regular vertices whose link is not a disc-like cap: we split it
//! there into [`BettiSegment`]s, each holding for the cuts from its start
//! vertex up to the next segment's start.
//!
//! Contours of a superarc are connected: β0 = 1; β2 = 1 iff closed; β1 =
//! β0 + β2 - χ (genus = β1 / 2 when closed).
//!
//! **Memory:** a table of 2^14 bytes, 12 bytes per supernode while peeling,
//! 24 bytes per segment; nothing per vertex.

use crate::field::Isovalue;
use crate::field::ScalarField;
use crate::mesh::{EDGE_OFFSETS, Mesh};
use crate::tree::{ArcId, ContourTree, Node};
use rayon::prelude::*;
use serde_json::{Value, json};

/// The topology of the contours of a stretch of one superarc.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BettiSegment {
    /// The vertex the stretch starts just above: the arc's lower node, or a
    /// regular vertex of the arc where the topology changes.
    pub start: u32,
    /// Euler characteristic χ of the contours.
    pub euler: i64,
    /// Number of boundary edges of the contour just above `start` (0 iff
    /// closed; the count itself varies within the stretch).
    pub boundary_edges: i64,
}

impl BettiSegment {
    /// True when the contours are closed surfaces (they miss the box).
    pub fn closed(&self) -> bool {
        self.boundary_edges == 0
    }

    /// (β0, β1, β2).
    pub fn betti(&self) -> [i64; 3] {
        let b2 = self.closed() as i64;
        [1, 1 + b2 - self.euler, b2]
    }

    /// Genus of the surface: χ = 2 - 2g - b, with b boundary loops unknown
    /// here, so for open contours this is β1 / 2 rounded down.
    pub fn genus(&self) -> i64 {
        self.betti()[1] / 2
    }
}

/// The Betti numbers of the contours of every superarc of a tree.
#[derive(Clone, Debug)]
pub struct ContourTopology {
    offsets: Vec<u32>,
    segments: Vec<BettiSegment>,
}

/// χ of every subset of a grid vertex's link, and which link edges exist.
struct LinkEuler {
    directions: Vec<[i64; 3]>,
    /// χ by bit mask over `directions`.
    chi: Vec<i8>,
    /// Link edges as pairs of direction indices.
    edges: Vec<(usize, usize)>,
    strides: Vec<i64>,
}

impl LinkEuler {
    fn new(grid: &crate::mesh::FreudenthalGrid) -> Self {
        let directions = grid.directions().to_vec();
        let k = directions.len();
        let is_offset = |d: [i64; 3]| {
            EDGE_OFFSETS
                .iter()
                .any(|o| *o == d || [-o[0], -o[1], -o[2]] == d)
        };
        let adj = |i: usize, j: usize| {
            let (a, b) = (directions[i], directions[j]);
            is_offset([a[0] - b[0], a[1] - b[1], a[2] - b[2]])
        };
        let mut edges = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..k {
            for j in i + 1..k {
                if adj(i, j) {
                    edges.push((i, j));
                    for l in j + 1..k {
                        if adj(i, l) && adj(j, l) {
                            triangles.push(1u32 << i | 1 << j | 1 << l);
                        }
                    }
                }
            }
        }
        let edge_masks: Vec<u32> = edges.iter().map(|&(i, j)| 1u32 << i | 1 << j).collect();
        let chi = (0u32..1 << k)
            .map(|m| {
                let e = edge_masks.iter().filter(|&&x| m & x == x).count() as i32;
                let t = triangles.iter().filter(|&&x| m & x == x).count() as i32;
                (m.count_ones() as i32 - e + t) as i8
            })
            .collect();
        let d = grid.dims();
        let strides = directions
            .iter()
            .map(|o| o[0] + d[0] as i64 * (o[1] + d[1] as i64 * o[2]))
            .collect();
        Self {
            directions,
            chi,
            edges,
            strides,
        }
    }

    /// (LS - US, Δ boundary edges) of vertex `v`.
    fn deltas(&self, field: &ScalarField, dims: [usize; 3], v: u32) -> (i64, i64) {
        let c = field.coords(v).map(|x| x as i64);
        let interior = (0..3).all(|a| dims[a] == 1 || (c[a] > 0 && c[a] + 1 < dims[a] as i64));
        let mut present = 0u32;
        let mut lower = 0u32;
        for (i, d) in self.directions.iter().enumerate() {
            let ok = interior
                || (0..3).all(|a| {
                    let n = c[a] + d[a];
                    n >= 0 && n < dims[a] as i64
                });
            if ok {
                present |= 1 << i;
                let u = (v as i64 + self.strides[i]) as u32;
                if field.is_above(v, u) {
                    lower |= 1 << i;
                }
            }
        }
        let upper = present & !lower;
        let dchi = self.chi[upper as usize] as i64 - self.chi[lower as usize] as i64;
        let mut dbe = 0;
        if !interior && dims.iter().all(|&d| d > 1) {
            for &(i, j) in &self.edges {
                if present & (1 << i) == 0 || present & (1 << j) == 0 {
                    continue;
                }
                let (di, dj) = (self.directions[i], self.directions[j]);
                // A boundary triangle lies in one face of the box: all three
                // vertices share a coordinate that is 0 or the last.
                let on_face = (0..3)
                    .any(|a| di[a] == 0 && dj[a] == 0 && (c[a] == 0 || c[a] + 1 == dims[a] as i64));
                if on_face {
                    let (li, lj) = (lower & (1 << i) != 0, lower & (1 << j) != 0);
                    if !li && !lj {
                        dbe += 1;
                    } else if li && lj {
                        dbe -= 1;
                    }
                }
            }
        }
        (dchi, dbe)
    }
}

impl ContourTopology {
    /// Computes χ, boundary and Betti numbers of the contours of every
    /// superarc of `tree` (the tree of `field`). Regular vertices are
    /// visited once, superarcs in parallel.
    pub fn new(tree: &ContourTree, field: &ScalarField) -> Self {
        let grid = field.mesh();
        let link = LinkEuler::new(&grid);
        let dims = field.dims();
        debug_assert_eq!(grid.num_vertices(), tree.num_vertices());
        // Per arc: the changes along it, relative to its bottom.
        let walks: Vec<(Vec<BettiSegment>, i64, i64)> = (0..tree.arcs().len() as u32)
            .into_par_iter()
            .map(|a| {
                let arc = ArcId(a);
                let lower = tree.node(tree.arc(arc).lower).vertex;
                let mut segs = vec![BettiSegment {
                    start: lower,
                    euler: 0,
                    boundary_edges: 0,
                }];
                let (mut chi, mut be) = (0i64, 0i64);
                for v in tree.arc_vertices(arc) {
                    let (dc, db) = link.deltas(field, dims, v);
                    if dc != 0 || db != 0 {
                        chi += dc;
                        be += db;
                        segs.push(BettiSegment {
                            start: v,
                            euler: chi,
                            boundary_edges: be,
                        });
                    }
                }
                (segs, chi, be)
            })
            .collect();
        let node_delta: Vec<(i64, i64)> = tree
            .nodes()
            .par_iter()
            .map(|n| link.deltas(field, dims, n.vertex))
            .collect();
        // Peel leaves: S_i = Σ χ_top(resolved down) - Σ χ_bottom(resolved
        // up) + (LS - US)_i; when one arc is left at i it balances S_i.
        let nodes = tree.nodes();
        let mut sum: Vec<(i64, i64)> = node_delta;
        let mut degree: Vec<u32> = nodes.iter().map(Node::degree).collect();
        let mut bottom: Vec<Option<(i64, i64)>> = vec![None; tree.arcs().len()];
        let mut queue: Vec<u32> = (0..nodes.len() as u32)
            .filter(|&i| degree[i as usize] == 1)
            .collect();
        while let Some(i) = queue.pop() {
            let id = crate::tree::NodeId(i);
            if degree[i as usize] != 1 {
                continue;
            }
            let up = tree
                .up_arcs(id)
                .iter()
                .find(|a| bottom[a.0 as usize].is_none());
            let down = tree
                .down_arcs(id)
                .iter()
                .find(|a| bottom[a.0 as usize].is_none());
            let s = sum[i as usize];
            let (arc, other) = match (up, down) {
                (Some(&e), _) => {
                    // i is e's lower node: χ_bottom(e) = S_i.
                    bottom[e.0 as usize] = Some(s);
                    let (_, dc, db) = &walks[e.0 as usize];
                    let j = tree.arc(e).upper;
                    let t = &mut sum[j.0 as usize];
                    t.0 += s.0 + dc;
                    t.1 += s.1 + db;
                    (e, j)
                }
                (None, Some(&e)) => {
                    // i is e's upper node: χ_top(e) = -S_i.
                    let (_, dc, db) = &walks[e.0 as usize];
                    let b = (-s.0 - dc, -s.1 - db);
                    bottom[e.0 as usize] = Some(b);
                    let j = tree.arc(e).lower;
                    let t = &mut sum[j.0 as usize];
                    t.0 -= b.0;
                    t.1 -= b.1;
                    (e, j)
                }
                (None, None) => continue,
            };
            let _ = arc;
            degree[i as usize] -= 1;
            degree[other.0 as usize] -= 1;
            if degree[other.0 as usize] == 1 {
                queue.push(other.0);
            }
        }
        let mut offsets = Vec::with_capacity(walks.len() + 1);
        offsets.push(0u32);
        let mut segments = Vec::new();
        for (a, (segs, _, _)) in walks.into_iter().enumerate() {
            let (c0, b0) = bottom[a].unwrap_or((0, 0));
            for s in segs {
                let s = BettiSegment {
                    start: s.start,
                    euler: c0 + s.euler,
                    boundary_edges: b0 + s.boundary_edges,
                };
                let same = segments.len() > offsets[a] as usize
                    && segments.last().is_some_and(|l: &BettiSegment| {
                        l.euler == s.euler && l.closed() == s.closed()
                    });
                if !same {
                    segments.push(s);
                }
            }
            offsets.push(segments.len() as u32);
        }
        Self { offsets, segments }
    }

    /// The stretches of superarc `arc`, ascending; never empty.
    pub fn segments(&self, arc: ArcId) -> &[BettiSegment] {
        let a = arc.0 as usize;
        &self.segments[self.offsets[a] as usize..self.offsets[a + 1] as usize]
    }

    /// The stretch of `arc` holding the contour at `iso` (which the arc
    /// must span): the last one starting below the cut.
    pub fn at(&self, arc: ArcId, field: &ScalarField, iso: Isovalue) -> &BettiSegment {
        let s = self.segments(arc);
        let i = s.partition_point(|seg| !iso.is_above(field, seg.start));
        &s[i.saturating_sub(1)]
    }

    /// Adds `"betti": [b0, b1, b2]` (the arc's lowest stretch) and
    /// `"euler"` to every arc of a tree's JSON (see [`crate::tree::json`]),
    /// and `"betti_segments": [{"start": VERTEX, "euler": χ, "betti": [..]},
    /// ...]` to the arcs whose topology changes along them.
    pub fn add_to_json(&self, json: &mut Value) {
        let Some(arcs) = json.get_mut("arcs").and_then(Value::as_array_mut) else {
            return;
        };
        for (a, arc) in arcs.iter_mut().enumerate() {
            self.add_to_arc_json(a, arc);
        }
    }

    /// [`Self::add_to_json`] for superarc `a`'s object alone.
    pub fn add_to_arc_json(&self, a: usize, arc: &mut Value) {
        if a + 1 >= self.offsets.len() {
            return;
        }
        let segs = self.segments(ArcId(a as u32));
        let Some(obj) = arc.as_object_mut() else {
            return;
        };
        obj.insert("betti".into(), json!(segs[0].betti()));
        obj.insert("euler".into(), json!(segs[0].euler));
        if segs.len() > 1 {
            let list: Vec<Value> = segs
                .iter()
                .map(|s| json!({"start": s.start, "euler": s.euler, "betti": s.betti()}))
                .collect();
            obj.insert("betti_segments".into(), Value::Array(list));
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::field::Values;
    use crate::progress::Progress;

    fn field(n: usize, f: impl Fn([f64; 3]) -> f64) -> ScalarField {
        let mut v = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = [x, y, z].map(|c| 2.0 * c as f64 / (n - 1) as f64 - 1.0);
                    v.push(f(p) as f32);
                }
            }
        }
        ScalarField::new([n; 3], Values::F32(v)).unwrap()
    }

    /// The superarc holding the contour at `h` of a field with one: the
    /// only arc whose lower end is below the cut and upper end above.
    fn only_contour(tree: &ContourTree, field: &ScalarField, h: f64) -> ArcId {
        let iso = Isovalue::new(h);
        let arcs: Vec<ArcId> = (0..tree.arcs().len() as u32)
            .map(ArcId)
            .filter(|&a| {
                let a = tree.arc(a);
                !iso.is_above(field, tree.node(a.lower).vertex)
                    && iso.is_above(field, tree.node(a.upper).vertex)
            })
            .collect();
        assert_eq!(arcs.len(), 1);
        arcs[0]
    }

    #[test]
    fn a_blob_has_sphere_contours() {
        let f = field(16, |p| {
            -(p[0] * p[0] + 1.2 * p[1] * p[1] + 1.4 * p[2] * p[2])
        });
        let (tree, _) = ContourTree::from_field(&f, &Progress::new()).unwrap();
        let topo = ContourTopology::new(&tree, &f);
        let arc = only_contour(&tree, &f, -0.5);
        let s = topo.at(arc, &f, Isovalue::new(-0.5));
        assert_eq!(
            (s.euler, s.closed(), s.betti(), s.genus()),
            (2, true, [1, 0, 1], 0)
        );
    }

    #[test]
    fn a_ramp_has_open_disc_contours() {
        let f = field(8, |p| p[0] + 0.3 * p[1] + 0.1 * p[2]);
        let (tree, _) = ContourTree::from_field(&f, &Progress::new()).unwrap();
        let topo = ContourTopology::new(&tree, &f);
        let arc = only_contour(&tree, &f, 0.1);
        let s = topo.at(arc, &f, Isovalue::new(0.1));
        assert_eq!((s.euler, s.closed(), s.betti()), (1, false, [1, 0, 0]));
    }

    #[test]
    fn json_gets_betti_per_arc() {
        let f = field(10, |p| {
            -(p[0] * p[0] + 1.2 * p[1] * p[1] + 1.4 * p[2] * p[2])
        });
        let (tree, _) = ContourTree::from_field(&f, &Progress::new()).unwrap();
        let mut json = crate::tree::json::tree_json(&tree, &f);
        ContourTopology::new(&tree, &f).add_to_json(&mut json);
        for arc in json["arcs"].as_array().unwrap() {
            assert_eq!(arc["betti"].as_array().unwrap().len(), 3);
            assert!(arc["euler"].is_i64());
        }
    }
}
