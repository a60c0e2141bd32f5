//! The contour tree: join and split sweeps, their merge, and the augmented
//! tree (Carr, Snoeyink, Axen: "Computing contour trees in all dimensions").
//!
//! Pipeline: vertex order (sorted by value, ties by id) -> join tree and
//! split tree sweeps, run in parallel -> merge by leaf cutting -> superarcs
//! with their regular vertices in value order.
//!
//! **Memory per vertex** (n vertices, beyond the field's own values):
//! building peaks at about 21 bytes (order 4, two union-finds 8, two parent
//! arrays 8, two degree arrays 2) during the sweeps and about 26 bytes
//! during the merge and augmentation; the finished tree keeps 8 bytes
//! (`vertex_arc` and `arc_vertices`) plus O(supernodes).

pub mod json;
mod merge;
pub mod raichel_seshadhri;
pub mod sweep;

use crate::field::{ScalarField, VertexOrder};
use crate::mesh::Mesh;
use crate::progress::{Cancelled, Progress};
use merge::NODE_FLAG;
use std::time::{Duration, Instant};

/// Index of a supernode in [`ContourTree::nodes`]. Nodes are sorted by the
/// vertex order, so comparing ids compares heights.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeId(pub u32);

/// Index of a superarc in [`ContourTree::arcs`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ArcId(pub u32);

/// A supernode: a critical vertex of the contour tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Node {
    /// The mesh vertex.
    pub vertex: u32,
    /// Number of superarcs going up (0 at a maximum, >= 2 at a join).
    pub up: u32,
    /// Number of superarcs going down (0 at a minimum, >= 2 at a split).
    pub down: u32,
}

/// What kind of critical point a node is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NodeKind {
    /// Local maximum: no arc up.
    Maximum,
    /// Local minimum: no arc down.
    Minimum,
    /// Several arcs up, one down: contours join going down.
    JoinSaddle,
    /// One arc up, several down: a contour splits going down.
    SplitSaddle,
    /// Several arcs up and down (a multi-saddle that is both).
    JoinSplitSaddle,
    /// One up, one down: only the global min/max of a one-vertex tree, or
    /// never otherwise.
    Regular,
}

impl Node {
    /// The kind of critical point.
    pub fn kind(&self) -> NodeKind {
        match (self.up, self.down) {
            (0, _) => NodeKind::Maximum,
            (_, 0) => NodeKind::Minimum,
            (1, 1) => NodeKind::Regular,
            (1, _) => NodeKind::SplitSaddle,
            (_, 1) => NodeKind::JoinSaddle,
            _ => NodeKind::JoinSplitSaddle,
        }
    }
}

/// A superarc: a monotone path between two supernodes through regular
/// vertices; every point on it stands for one contour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Superarc {
    /// The higher end in the vertex order.
    pub upper: NodeId,
    /// The lower end.
    pub lower: NodeId,
}

/// What lies at a vertex in the augmented tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexPlace {
    /// The vertex is a supernode.
    Node(NodeId),
    /// The vertex is regular, inside this superarc.
    Arc(ArcId),
}

/// The augmented contour tree of a scalar field on a mesh.
#[derive(Clone, Debug)]
pub struct ContourTree {
    nodes: Vec<Node>,
    arcs: Vec<Superarc>,
    /// Per vertex: its superarc, or `NODE_FLAG | node`.
    vertex_arc: Vec<u32>,
    /// Regular vertices of arc `a`: `arc_vertices[arc_offsets[a]..arc_offsets[a+1]]`,
    /// ascending in the vertex order.
    arc_offsets: Vec<u32>,
    arc_vertices: Vec<u32>,
    /// Arcs at node `v`: `node_arcs[node_offsets[v]..]`, the up arcs first.
    node_offsets: Vec<u32>,
    node_arcs: Vec<ArcId>,
}

/// Seconds spent in each stage of [`ContourTree::from_field`].
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildTimes {
    /// Sorting the vertices.
    pub sort: Duration,
    /// Classifying every vertex's link (part of `sweeps`).
    pub links: Duration,
    /// Join tree sweep (in parallel with the split sweep).
    pub join: Duration,
    /// Split tree sweep.
    pub split: Duration,
    /// Link classification and both sweeps, wall clock.
    pub sweeps: Duration,
    /// Merging into the contour tree.
    pub merge: Duration,
    /// Grouping regular vertices into superarcs.
    pub augment: Duration,
}

impl BuildTimes {
    /// Wall-clock total.
    pub fn total(&self) -> Duration {
        self.sort + self.sweeps + self.merge + self.augment
    }
}

impl ContourTree {
    /// Builds the tree of a grid field on its Freudenthal triangulation.
    pub fn from_field(
        field: &ScalarField,
        progress: &Progress,
    ) -> Result<(Self, BuildTimes), Cancelled> {
        let t = Instant::now();
        progress.stage("sort");
        let order = field.vertex_order();
        let sort = t.elapsed();
        let mesh = field.mesh();
        let (tree, mut times) = crate::with_values!(field.values(), v => Self::build(&mesh, v.as_slice(), &order, progress))?;
        times.sort = sort;
        Ok((tree, times))
    }

    /// Builds the tree of any mesh given its vertex order: `values` compares
    /// two vertices, `order` lists them ascending.
    pub fn build<M: Mesh, O: VertexOrder + ?Sized>(
        mesh: &M,
        values: &O,
        order: &[u32],
        progress: &Progress,
    ) -> Result<(Self, BuildTimes), Cancelled> {
        assert_eq!(mesh.num_vertices(), order.len(), "order covers the mesh");
        let mut times = BuildTimes::default();
        if order.is_empty() {
            return Ok((
                Self::assemble(Vec::new(), Vec::new(), Vec::new(), vec![0], Vec::new()),
                times,
            ));
        }
        progress.stage("join and split trees");
        let t = Instant::now();
        let codes = sweep::link_codes(mesh, values);
        times.links = t.elapsed();
        let (join, split) = rayon::join(
            || {
                let t = Instant::now();
                sweep::sweep(mesh, values, &codes, true, order, progress).map(|s| (s, t.elapsed()))
            },
            || {
                let t = Instant::now();
                sweep::sweep(mesh, values, &codes, false, order, &Progress::new())
                    .map(|s| (s, t.elapsed()))
            },
        );
        let ((join, tj), (split, ts)) = (join?, split?);
        drop(codes);
        progress.check(0, 1)?;
        times.join = tj;
        times.split = ts;
        times.sweeps = t.elapsed();
        progress.stage("merge");
        let t = Instant::now();
        let merged = merge::merge(join, split, order, progress)?;
        times.merge = t.elapsed();
        progress.stage("augment");
        let t = Instant::now();
        let tree = merge::augment(merged, order);
        times.augment = t.elapsed();
        Ok((tree, times))
    }

    pub(crate) fn assemble(
        nodes: Vec<Node>,
        arcs: Vec<Superarc>,
        mut vertex_arc: Vec<u32>,
        arc_offsets: Vec<u32>,
        arc_vertices: Vec<u32>,
    ) -> Self {
        // Canonical arc order: by lower node, then upper node. Renumber.
        let mut perm: Vec<u32> = (0..arcs.len() as u32).collect();
        perm.sort_unstable_by_key(|&a| (arcs[a as usize].lower, arcs[a as usize].upper));
        let mut new_id = vec![0u32; arcs.len()];
        for (new, &old) in perm.iter().enumerate() {
            new_id[old as usize] = new as u32;
        }
        let sorted_arcs: Vec<Superarc> = perm.iter().map(|&a| arcs[a as usize]).collect();
        let mut offsets = vec![0u32; arcs.len() + 1];
        let mut verts = Vec::with_capacity(arc_vertices.len());
        for (new, &old) in perm.iter().enumerate() {
            let r = arc_offsets[old as usize] as usize..arc_offsets[old as usize + 1] as usize;
            verts.extend_from_slice(&arc_vertices[r]);
            offsets[new + 1] = verts.len() as u32;
        }
        drop(arc_vertices);
        for va in vertex_arc.iter_mut() {
            if *va & NODE_FLAG == 0 {
                *va = new_id[*va as usize];
            }
        }
        // Node adjacency: up arcs (where the node is the lower end) first.
        let mut node_offsets = vec![0u32; nodes.len() + 1];
        for (i, n) in nodes.iter().enumerate() {
            node_offsets[i + 1] = node_offsets[i] + n.up + n.down;
        }
        let mut fill_up: Vec<u32> = node_offsets[..nodes.len()].to_vec();
        let mut fill_down: Vec<u32> = nodes
            .iter()
            .enumerate()
            .map(|(i, n)| node_offsets[i] + n.up)
            .collect();
        let mut node_arcs = vec![ArcId(0); node_offsets[nodes.len()] as usize];
        for (a, arc) in sorted_arcs.iter().enumerate() {
            let l = arc.lower.0 as usize;
            node_arcs[fill_up[l] as usize] = ArcId(a as u32);
            fill_up[l] += 1;
            let u = arc.upper.0 as usize;
            node_arcs[fill_down[u] as usize] = ArcId(a as u32);
            fill_down[u] += 1;
        }
        Self {
            nodes,
            arcs: sorted_arcs,
            vertex_arc,
            arc_offsets: offsets,
            arc_vertices: verts,
            node_offsets,
            node_arcs,
        }
    }

    /// The supernodes, ascending in the vertex order.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// One supernode.
    pub fn node(&self, id: NodeId) -> &Node {
        &self.nodes[id.0 as usize]
    }

    /// The superarcs, sorted by (lower, upper).
    pub fn arcs(&self) -> &[Superarc] {
        &self.arcs
    }

    /// One superarc.
    pub fn arc(&self, id: ArcId) -> &Superarc {
        &self.arcs[id.0 as usize]
    }

    /// Number of mesh vertices.
    pub fn num_vertices(&self) -> usize {
        self.vertex_arc.len()
    }

    /// The regular vertices of a superarc, ascending in the vertex order
    /// (its ends, the supernodes, are not included).
    pub fn arc_vertices(&self, id: ArcId) -> &[u32] {
        let a = id.0 as usize;
        &self.arc_vertices[self.arc_offsets[a] as usize..self.arc_offsets[a + 1] as usize]
    }

    /// Where vertex `v` lies: on a superarc or at a supernode.
    pub fn place(&self, v: u32) -> VertexPlace {
        let va = self.vertex_arc[v as usize];
        if va & NODE_FLAG != 0 {
            VertexPlace::Node(NodeId(va & !NODE_FLAG))
        } else {
            VertexPlace::Arc(ArcId(va))
        }
    }

    /// The superarcs going up from a node (the node is their lower end).
    pub fn up_arcs(&self, id: NodeId) -> &[ArcId] {
        let i = id.0 as usize;
        let s = self.node_offsets[i] as usize;
        &self.node_arcs[s..s + self.nodes[i].up as usize]
    }

    /// The superarcs going down from a node (the node is their upper end).
    pub fn down_arcs(&self, id: NodeId) -> &[ArcId] {
        let i = id.0 as usize;
        let s = self.node_offsets[i] as usize + self.nodes[i].up as usize;
        &self.node_arcs[s..self.node_offsets[i + 1] as usize]
    }

    /// Count of nodes of each kind: (maxima, minima, join saddles, split
    /// saddles). A node that is both a join and a split counts as both.
    pub fn kind_counts(&self) -> (usize, usize, usize, usize) {
        let mut c = (0, 0, 0, 0);
        for n in &self.nodes {
            if n.up == 0 {
                c.0 += 1;
            }
            if n.down == 0 {
                c.1 += 1;
            }
            if n.up >= 2 {
                c.2 += 1;
            }
            if n.down >= 2 {
                c.3 += 1;
            }
        }
        c
    }

    /// Heap bytes held by the tree.
    pub fn heap_bytes(&self) -> usize {
        self.nodes.capacity() * size_of::<Node>()
            + self.arcs.capacity() * size_of::<Superarc>()
            + (self.vertex_arc.capacity()
                + self.arc_offsets.capacity()
                + self.arc_vertices.capacity()
                + self.node_offsets.capacity()
                + self.node_arcs.capacity())
                * 4
    }
}
