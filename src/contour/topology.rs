//! Combinatorial and geometric measures of an extracted contour mesh:
//! counts, Euler characteristic V - E + F, boundary, manifoldness,
//! orientation, components, genus, area and enclosed volume.

use super::marching::Cancelled;
use rayon::prelude::*;

/// What an indexed triangle mesh is, combinatorially and geometrically.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshTopology {
    /// Vertices used by some triangle.
    pub vertices: usize,
    /// Distinct edges.
    pub edges: usize,
    /// Triangles.
    pub triangles: usize,
    /// Edges of exactly one triangle.
    pub boundary_edges: usize,
    /// Closed loops the boundary edges form.
    pub boundary_loops: usize,
    /// Edges of more than two triangles.
    pub non_manifold_edges: usize,
    /// Interior edges not walked once in each direction by their two
    /// triangles (0 for a consistently oriented mesh).
    pub misoriented_edges: usize,
    /// Vertices whose triangles do not form a single fan.
    pub non_manifold_vertices: usize,
    /// Connected components (triangles joined through shared vertices).
    pub components: usize,
    /// V - E + F.
    pub euler: i64,
    /// Total area (world units squared).
    pub area: f64,
    /// |signed volume| by the divergence theorem; meaningful when closed.
    pub volume: f64,
}

impl MeshTopology {
    /// Measures a mesh, in time linear in its size: the corners are
    /// grouped by vertex (counting sort), and each vertex then settles the
    /// edges to its higher neighbours (both directions of an edge are
    /// corners of its lower end: `v -> w` as a corner's next, `w -> v` as
    /// a corner's previous) and its own link, in parallel.
    pub fn of(positions: &[[f32; 3]], indices: &[u32]) -> Self {
        Self::measure(positions, indices, &|| false).expect("nothing cancels it")
    }

    /// [`MeshTopology::of`], stopped soon after `cancel` says so: a head
    /// surface of millions of triangles takes over half a second, which
    /// must not hold a core that the next drag step needs. `cancel` is
    /// asked between the passes and every few thousand triangles or
    /// vertices within them.
    pub fn measure(
        positions: &[[f32; 3]],
        indices: &[u32],
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Result<Self, Cancelled> {
        /// Items between two questions to `cancel`.
        const ASK: usize = 1 << 14;
        let check = || if cancel() { Err(Cancelled) } else { Ok(()) };
        let n = positions.len();
        let triangles = indices.len() / 3;
        let indices = &indices[..3 * triangles];
        check()?;
        // Corners by vertex: (previous, next) around each triangle.
        let mut start = vec![0u32; n + 1];
        for &v in indices {
            start[v as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        check()?;
        let mut fill = start.clone();
        let mut corners = vec![(0u32, 0u32); indices.len()];
        for run in indices.chunks(3 * ASK) {
            check()?;
            for t in run.chunks_exact(3) {
                for i in 0..3 {
                    let v = t[i] as usize;
                    corners[fill[v] as usize] = (t[(i + 2) % 3], t[(i + 1) % 3]);
                    fill[v] += 1;
                }
            }
        }
        drop(fill);
        let per_vertex = (0..n)
            .into_par_iter()
            .with_min_len(ASK)
            .try_fold(VertexTally::default, |mut acc, v| {
                if v % ASK == 0 {
                    check()?;
                }
                let c = &corners[start[v] as usize..start[v + 1] as usize];
                acc.add(v as u32, c);
                Ok(acc)
            })
            .try_reduce(VertexTally::default, |a, b| Ok(VertexTally::merge(a, b)))?;
        let (area, volume) = indices
            .par_chunks(3 * 4096)
            .map(|chunk| {
                check()?;
                let (mut area, mut volume) = (0f64, 0f64);
                for tri in chunk.chunks_exact(3) {
                    let p = [0, 1, 2].map(|i| positions[tri[i] as usize].map(|c| c as f64));
                    area += triangle_area(positions, tri);
                    let c = [
                        p[1][1] * p[2][2] - p[1][2] * p[2][1],
                        p[1][2] * p[2][0] - p[1][0] * p[2][2],
                        p[1][0] * p[2][1] - p[1][1] * p[2][0],
                    ];
                    volume += (p[0][0] * c[0] + p[0][1] * c[1] + p[0][2] * c[2]) / 6.0;
                }
                Ok((area, volume))
            })
            .try_reduce(|| (0.0, 0.0), |a, b| Ok((a.0 + b.0, a.1 + b.1)))?;
        // Components through shared vertices, boundary loops through
        // boundary edges.
        let mut uf = UnionFind::new(n);
        for run in indices.chunks(3 * ASK) {
            check()?;
            for t in run.chunks_exact(3) {
                uf.union(t[0], t[1]);
                uf.union(t[0], t[2]);
            }
        }
        let mut boundary = UnionFind::new(n);
        let mut boundary_vertices = Vec::with_capacity(2 * per_vertex.boundary.len());
        for &(a, b) in &per_vertex.boundary {
            boundary.union(a, b);
            boundary_vertices.extend([a, b]);
        }
        boundary_vertices.sort_unstable();
        boundary_vertices.dedup();
        let used = |v: usize| start[v] < start[v + 1];
        let vertices = (0..n).filter(|&v| used(v)).count();
        Ok(MeshTopology {
            vertices,
            edges: per_vertex.edges,
            triangles,
            boundary_edges: per_vertex.boundary.len(),
            boundary_loops: boundary_vertices
                .iter()
                .filter(|&&v| boundary.find(v) == v)
                .count(),
            non_manifold_edges: per_vertex.non_manifold_edges,
            misoriented_edges: per_vertex.misoriented_edges,
            non_manifold_vertices: per_vertex.non_manifold_vertices,
            components: (0..n as u32)
                .filter(|&v| used(v as usize) && uf.find(v) == v)
                .count(),
            euler: vertices as i64 - per_vertex.edges as i64 + triangles as i64,
            area,
            volume: volume.abs(),
        })
    }

    /// Betti numbers (β0, β1, β2) of a connected surface: β2 = 1 iff
    /// closed, β1 = β0 + β2 - χ.
    pub fn betti(&self) -> [i64; 3] {
        let b0 = self.components as i64;
        let b2 = if self.boundary_edges == 0 { b0 } else { 0 };
        [b0, b0 + b2 - self.euler, b2]
    }

    /// Genus of a connected orientable surface: χ = 2 - 2g - (boundary loops).
    pub fn genus(&self) -> i64 {
        (2 * self.components as i64 - self.boundary_loops as i64 - self.euler) / 2
    }

    /// Closed: no boundary edge.
    pub fn is_closed(&self) -> bool {
        self.boundary_edges == 0
    }
}

/// What the vertices of a mesh say about its edges and links: each edge
/// is counted at its lower end, each vertex's link at the vertex.
#[derive(Default)]
struct VertexTally {
    edges: usize,
    /// Edges of one triangle, as (lower end, upper end).
    boundary: Vec<(u32, u32)>,
    non_manifold_edges: usize,
    misoriented_edges: usize,
    non_manifold_vertices: usize,
    /// Scratch: (higher neighbour, walked away from v) per corner.
    out: Vec<(u32, bool)>,
    /// Scratch: the link's vertices and their union-find parents.
    link: Vec<u32>,
    parent: Vec<usize>,
}

impl VertexTally {
    /// Vertex `v` with its corners (previous, next).
    fn add(&mut self, v: u32, corners: &[(u32, u32)]) {
        if corners.is_empty() {
            return;
        }
        // Edges to higher neighbours: v -> next walks away from v, and
        // prev -> v towards it.
        self.out.clear();
        for &(prev, next) in corners {
            if next > v {
                self.out.push((next, true));
            }
            if prev > v {
                self.out.push((prev, false));
            }
        }
        self.out.sort_unstable();
        let mut i = 0;
        while i < self.out.len() {
            let w = self.out[i].0;
            let mut j = i;
            let (mut away, mut back) = (0, 0);
            while j < self.out.len() && self.out[j].0 == w {
                if self.out[j].1 {
                    away += 1;
                } else {
                    back += 1;
                }
                j += 1;
            }
            self.edges += 1;
            match (away, back) {
                (1, 0) | (0, 1) => self.boundary.push((v, w)),
                (1, 1) => {}
                (2, 0) | (0, 2) => self.misoriented_edges += 1,
                _ => self.non_manifold_edges += 1,
            }
            i = j;
        }
        // The link of v: edges prev - next; one fan iff one component.
        self.link.clear();
        for &(prev, next) in corners {
            self.link.extend([prev, next]);
        }
        self.link.sort_unstable();
        self.link.dedup();
        self.parent.clear();
        self.parent.extend(0..self.link.len());
        fn root(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        let mut components = self.link.len();
        for &(prev, next) in corners {
            let a = self.link.partition_point(|&x| x < prev);
            let b = self.link.partition_point(|&x| x < next);
            let (ra, rb) = (root(&mut self.parent, a), root(&mut self.parent, b));
            if ra != rb {
                self.parent[ra] = rb;
                components -= 1;
            }
        }
        if components != 1 {
            self.non_manifold_vertices += 1;
        }
    }

    fn merge(mut self, other: Self) -> Self {
        self.edges += other.edges;
        self.boundary.extend(other.boundary);
        self.non_manifold_edges += other.non_manifold_edges;
        self.misoriented_edges += other.misoriented_edges;
        self.non_manifold_vertices += other.non_manifold_vertices;
        self
    }
}

struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
        }
    }

    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = p;
            x = p;
        }
        x
    }

    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra as usize] = rb;
        }
    }
}

/// The area of triangle `tri` (three indices into `positions`), in
/// float64 from the stored float32 corners.
pub fn triangle_area(positions: &[[f32; 3]], tri: &[u32]) -> f64 {
    let p = [0, 1, 2].map(|i| positions[tri[i] as usize].map(f64::from));
    let u = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
    let v = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::follow::IdBuildHasher;
    use proptest::prelude::*;
    use std::collections::HashMap;

    /// The first implementation (a hash map of edges): the oracle.
    fn of_by_hashing(positions: &[[f32; 3]], indices: &[u32]) -> MeshTopology {
        let triangles = indices.len() / 3;
        // Directed edge counts per undirected edge: (forward, backward).
        let mut edges: HashMap<u64, (u32, u32), IdBuildHasher> = HashMap::default();
        let mut uf = UnionFind::new(positions.len());
        let mut used = vec![false; positions.len()];
        let (mut area, mut volume) = (0f64, 0f64);
        for tri in indices.chunks_exact(3) {
            for i in 0..3 {
                let (a, b) = (tri[i], tri[(i + 1) % 3]);
                let e = edges
                    .entry((a.min(b) as u64) << 32 | a.max(b) as u64)
                    .or_default();
                if a < b {
                    e.0 += 1;
                } else {
                    e.1 += 1;
                }
                used[a as usize] = true;
                uf.union(a, b);
            }
            let p = [0, 1, 2].map(|i| positions[tri[i] as usize].map(|c| c as f64));
            area += triangle_area(positions, tri);
            let c = [
                p[1][1] * p[2][2] - p[1][2] * p[2][1],
                p[1][2] * p[2][0] - p[1][0] * p[2][2],
                p[1][0] * p[2][1] - p[1][1] * p[2][0],
            ];
            volume += (p[0][0] * c[0] + p[0][1] * c[1] + p[0][2] * c[2]) / 6.0;
        }
        let vertices = used.iter().filter(|&&u| u).count();
        let mut t = MeshTopology {
            vertices,
            edges: edges.len(),
            triangles,
            euler: vertices as i64 - edges.len() as i64 + triangles as i64,
            area,
            volume: volume.abs(),
            ..Default::default()
        };
        let mut boundary = UnionFind::new(positions.len());
        let mut boundary_vertices = Vec::new();
        for (&k, &(f, b)) in &edges {
            let (a, c) = ((k >> 32) as u32, k as u32);
            match f + b {
                1 => {
                    t.boundary_edges += 1;
                    boundary.union(a, c);
                    boundary_vertices.push(a);
                    boundary_vertices.push(c);
                }
                2 if f == 1 => {}
                2 => t.misoriented_edges += 1,
                _ => t.non_manifold_edges += 1,
            }
        }
        boundary_vertices.sort_unstable();
        boundary_vertices.dedup();
        t.boundary_loops = boundary_vertices
            .iter()
            .filter(|&&v| boundary.find(v) == v)
            .count();
        t.components = (0..positions.len() as u32)
            .filter(|&v| used[v as usize] && uf.find(v) == v)
            .count();
        t.non_manifold_vertices = count_non_manifold_vertices(indices);
        t
    }

    /// Vertices whose incident triangles do not form one fan (one connected
    /// link, joined through the edges at the vertex).
    fn count_non_manifold_vertices(indices: &[u32]) -> usize {
        // (vertex, previous, next) for every corner.
        let mut corners: Vec<[u32; 3]> = indices
            .chunks_exact(3)
            .flat_map(|t| (0..3).map(move |i| [t[i], t[(i + 2) % 3], t[(i + 1) % 3]]))
            .collect();
        corners.sort_unstable();
        let mut bad = 0;
        let mut i = 0;
        while i < corners.len() {
            let v = corners[i][0];
            let mut j = i;
            while j < corners.len() && corners[j][0] == v {
                j += 1;
            }
            // Link graph of v: edges prev-next; count its components.
            let mut ids: Vec<u32> = corners[i..j].iter().flat_map(|c| [c[1], c[2]]).collect();
            ids.sort_unstable();
            ids.dedup();
            let mut parent: Vec<usize> = (0..ids.len()).collect();
            fn root(p: &mut [usize], mut x: usize) -> usize {
                while p[x] != x {
                    p[x] = p[p[x]];
                    x = p[x];
                }
                x
            }
            for c in &corners[i..j] {
                let a = ids.partition_point(|&x| x < c[1]);
                let b = ids.partition_point(|&x| x < c[2]);
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                parent[ra] = rb;
            }
            let comps = (0..ids.len())
                .filter(|&x| root(&mut parent, x) == x)
                .count();
            if comps != 1 {
                bad += 1;
            }
            i = j;
        }
        bad
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(500))]

        /// Random triangle soups over few vertices: shared, reversed,
        /// repeated and dangling edges, isolated and pinched vertices.
        #[test]
        fn linear_pass_equals_hashing(
            n in 3usize..12,
            tris in proptest::collection::vec((0u32..12, 0u32..12, 0u32..12), 0..30),
        ) {
            let positions: Vec<[f32; 3]> = (0..n)
                .map(|i| [i as f32, (i * i % 7) as f32, (i * 3 % 5) as f32])
                .collect();
            let indices: Vec<u32> = tris
                .into_iter()
                .map(|(a, b, c)| [a % n as u32, b % n as u32, c % n as u32])
                .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
                .flatten()
                .collect();
            let fast = MeshTopology::of(&positions, &indices);
            let slow = of_by_hashing(&positions, &indices);
            prop_assert_eq!(
                (fast.vertices, fast.edges, fast.triangles, fast.boundary_edges, fast.boundary_loops),
                (slow.vertices, slow.edges, slow.triangles, slow.boundary_edges, slow.boundary_loops)
            );
            prop_assert_eq!(
                (fast.non_manifold_edges, fast.misoriented_edges, fast.components, fast.euler),
                (slow.non_manifold_edges, slow.misoriented_edges, slow.components, slow.euler)
            );
            prop_assert_eq!(fast.non_manifold_vertices, slow.non_manifold_vertices);
            prop_assert!((fast.area - slow.area).abs() <= 1e-9 * (1.0 + slow.area));
            prop_assert!((fast.volume - slow.volume).abs() <= 1e-9 * (1.0 + slow.volume));
        }
    }

    #[test]
    fn a_closed_octahedron_and_an_open_square() {
        let p = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let octahedron = [
            0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5,
        ];
        let t = MeshTopology::of(&p, &octahedron);
        assert_eq!((t.vertices, t.edges, t.triangles, t.euler), (6, 12, 8, 2));
        assert!(t.is_closed());
        assert_eq!(
            (t.genus(), t.misoriented_edges, t.non_manifold_vertices),
            (0, 0, 0)
        );
        assert!((t.volume - 4.0 / 3.0).abs() < 1e-9);
        let square = MeshTopology::of(&p[..4], &[0, 2, 1, 0, 1, 3]);
        assert_eq!(
            (square.boundary_edges, square.boundary_loops, square.euler),
            (4, 1, 1)
        );
    }

    /// A measurement stops at whichever question to `cancel` says yes (the
    /// first, one in the middle of a pass, the last) and is otherwise the
    /// one [`MeshTopology::of`] makes: a strip of 2 x 100k triangles, long
    /// enough for every pass to ask more than once.
    #[test]
    fn a_measurement_stops_when_cancelled() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let n = 100_000u32;
        let positions: Vec<[f32; 3]> = (0..=n)
            .flat_map(|i| [[i as f32, 0.0, 0.0], [i as f32, 1.0, 0.0]])
            .collect();
        let indices: Vec<u32> = (0..n)
            .flat_map(|i| [2 * i, 2 * i + 2, 2 * i + 1, 2 * i + 1, 2 * i + 2, 2 * i + 3])
            .collect();
        let asked = AtomicUsize::new(0);
        let whole = MeshTopology::measure(&positions, &indices, &|| {
            asked.fetch_add(1, Ordering::Relaxed);
            false
        })
        .expect("never cancelled");
        assert_eq!(whole, MeshTopology::of(&positions, &indices));
        assert_eq!((whole.euler, whole.boundary_loops), (1, 1));
        let questions = asked.load(Ordering::Relaxed);
        assert!(questions > 20, "asked only {questions} times");
        for stop_at in [0, questions / 2, questions - 1] {
            let asked = AtomicUsize::new(0);
            let cancel = || asked.fetch_add(1, Ordering::Relaxed) >= stop_at;
            assert_eq!(
                MeshTopology::measure(&positions, &indices, &cancel),
                Err(Cancelled),
                "cancelled at question {stop_at} of {questions}"
            );
        }
    }
}
