//! Combinatorial and geometric measures of an extracted contour mesh:
//! counts, Euler characteristic V - E + F, boundary, manifoldness,
//! orientation, components, genus, area and enclosed volume.

use super::follow::IdBuildHasher;
use std::collections::HashMap;

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
    /// Measures a mesh.
    pub fn of(positions: &[[f32; 3]], indices: &[u32]) -> Self {
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
            let u = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
            let v = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            area += 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
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
