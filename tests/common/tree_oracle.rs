//! Brute-force oracles of the contour tree, from the definitions on the
//! mesh and not from the engines' code (used by tests/tree_oracle.rs and
//! tests/raichel_seshadhri.rs):
//!
//! (a) the join and split trees recomputed from the output contour tree equal
//!     those computed by definition (Carr et al. Def. 4.1) by flooding the
//!     superlevel / sublevel sets on the mesh;
//! (b) every vertex's up/down degree equals the number of components of
//!     {f > f(v)} / {f < f(v)} (vertex order) adjacent to v, by flooding;
//! (c) for isovalues h that are not vertex values, the number of superarcs
//!     spanning h equals the number of components of the level set {f = h},
//!     found by flooding the simplices h crosses through shared crossed
//!     facets.

use flexiso::field::{ScalarField, Values};
use flexiso::mesh::{FreudenthalGrid, Mesh};
use flexiso::tree::{ArcId, ContourTree, VertexPlace};
use std::collections::{BTreeSet, HashMap};

/// Position of each vertex in the vertex order (value, id).
pub fn ranks(field: &ScalarField) -> Vec<usize> {
    let n = field.len();
    let mut ids: Vec<u32> = (0..n as u32).collect();
    ids.sort_by(|&a, &b| {
        field
            .value(a)
            .partial_cmp(&field.value(b))
            .expect("finite")
            .then(a.cmp(&b))
    });
    let mut rank = vec![0; n];
    for (r, &v) in ids.iter().enumerate() {
        rank[v as usize] = r;
    }
    rank
}

pub fn neighbours(mesh: &FreudenthalGrid, v: usize) -> Vec<usize> {
    let mut out = Vec::new();
    mesh.for_each_neighbour(v as u32, |u| out.push(u as usize));
    out
}

/// Components of the set {w : keep(w)}, by flooding; returns a label per
/// vertex (usize::MAX outside the set).
pub fn flood_components(mesh: &FreudenthalGrid, keep: impl Fn(usize) -> bool) -> Vec<usize> {
    let n = mesh.num_vertices();
    let mut label = vec![usize::MAX; n];
    let mut next = 0;
    for s in 0..n {
        if !keep(s) || label[s] != usize::MAX {
            continue;
        }
        let mut stack = vec![s];
        label[s] = next;
        while let Some(v) = stack.pop() {
            for u in neighbours(mesh, v) {
                if keep(u) && label[u] == usize::MAX {
                    label[u] = next;
                    stack.push(u);
                }
            }
        }
        next += 1;
    }
    label
}

/// Augmented join tree by definition: for each vertex v, each component C
/// of {w > v} adjacent to v contributes the edge (lowest vertex of C, v).
/// With `up = false`, the split tree (components of {w < v}, highest vertex).
pub fn sweep_tree_by_definition(
    mesh: &FreudenthalGrid,
    rank: &[usize],
    up: bool,
) -> BTreeSet<(usize, usize)> {
    let n = rank.len();
    let mut edges = BTreeSet::new();
    for v in 0..n {
        let beyond = |w: usize| {
            if up {
                rank[w] > rank[v]
            } else {
                rank[w] < rank[v]
            }
        };
        let label = flood_components(mesh, beyond);
        let adjacent: BTreeSet<usize> = neighbours(mesh, v)
            .into_iter()
            .filter(|&u| beyond(u))
            .map(|u| label[u])
            .collect();
        for c in adjacent {
            let extreme = (0..n)
                .filter(|&w| label[w] == c)
                .min_by_key(|&w| if up { rank[w] } else { n - rank[w] })
                .expect("component is not empty");
            edges.insert((extreme, v));
        }
    }
    edges
}

/// The augmented contour tree's edges, vertex to vertex.
pub fn augmented_edges(tree: &ContourTree) -> Vec<(usize, usize)> {
    let mut edges = Vec::new();
    for (a, arc) in tree.arcs().iter().enumerate() {
        let mut chain = vec![tree.node(arc.lower).vertex as usize];
        chain.extend(
            tree.arc_vertices(ArcId(a as u32))
                .iter()
                .map(|v| v as usize),
        );
        chain.push(tree.node(arc.upper).vertex as usize);
        for w in chain.windows(2) {
            edges.push((w[0], w[1]));
        }
    }
    edges
}

/// Join (up = true) or split tree of a *tree graph* by a union-find sweep:
/// an independent way to get them from the output.
pub fn sweep_tree_of_graph(
    n: usize,
    edges: &[(usize, usize)],
    rank: &[usize],
    up: bool,
) -> BTreeSet<(usize, usize)> {
    let mut adj = vec![Vec::new(); n];
    for &(a, b) in edges {
        adj[a].push(b);
        adj[b].push(a);
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&v| rank[v]);
    if up {
        order.reverse();
    }
    let mut parent: Vec<usize> = (0..n).collect();
    let mut extreme: Vec<usize> = (0..n).collect();
    let mut seen = vec![false; n];
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let mut out = BTreeSet::new();
    for &v in &order {
        seen[v] = true;
        for &u in &adj[v] {
            if !seen[u] {
                continue;
            }
            let (ru, rv) = (find(&mut parent, u), find(&mut parent, v));
            if ru != rv {
                out.insert((extreme[ru], v));
                parent[ru] = rv;
                extreme[rv] = v;
            }
        }
    }
    out
}

/// The top simplices of the Freudenthal triangulation of the grid: for every
/// cell of the non-trivial axes, one simplex per permutation of those axes
/// (the monotone lattice paths from the cell's low corner to its high one).
pub fn top_simplices(dims: [usize; 3]) -> Vec<Vec<usize>> {
    let axes: Vec<usize> = (0..3).filter(|&a| dims[a] > 1).collect();
    let stride = [1, dims[0], dims[0] * dims[1]];
    let mut perms: Vec<Vec<usize>> = vec![vec![]];
    for _ in 0..axes.len() {
        let mut next = Vec::new();
        for p in &perms {
            for &a in &axes {
                if !p.contains(&a) {
                    let mut q = p.clone();
                    q.push(a);
                    next.push(q);
                }
            }
        }
        perms = next;
    }
    let mut out = Vec::new();
    for z in 0..dims[2].max(2) - 1 {
        for y in 0..dims[1].max(2) - 1 {
            for x in 0..dims[0].max(2) - 1 {
                let base = x + dims[0] * (y + dims[1] * z);
                for p in &perms {
                    let mut s = vec![base];
                    let mut v = base;
                    for &a in p {
                        v += stride[a];
                        s.push(v);
                    }
                    out.push(s);
                }
            }
        }
    }
    out
}

/// Components of the level set {f = h} (h not a vertex value): simplices that
/// h crosses, joined through shared facets that h also crosses.
pub fn level_set_components(field: &ScalarField, h: f64) -> usize {
    let dims = field.dims();
    let crossed = |s: &[usize]| {
        s.iter().any(|&v| field.value(v as u32) < h) && s.iter().any(|&v| field.value(v as u32) > h)
    };
    let simplices: Vec<Vec<usize>> = top_simplices(dims)
        .into_iter()
        .filter(|s| crossed(s))
        .collect();
    if simplices.is_empty() {
        return 0;
    }
    if simplices[0].len() == 2 {
        return simplices.len(); // 1D: every crossing is a point of its own
    }
    let mut parent: Vec<usize> = (0..simplices.len()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let mut by_facet: HashMap<Vec<usize>, usize> = HashMap::new();
    for (i, s) in simplices.iter().enumerate() {
        for skip in 0..s.len() {
            let mut facet: Vec<usize> = s
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != skip)
                .map(|(_, &v)| v)
                .collect();
            if !crossed(&facet) {
                continue;
            }
            facet.sort_unstable();
            if let Some(&j) = by_facet.get(&facet) {
                let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                parent[a] = b;
            } else {
                by_facet.insert(facet, i);
            }
        }
    }
    (0..simplices.len())
        .filter(|&i| find(&mut parent, i) == i)
        .count()
}

/// Checks (a), (b), (c) and the tree's own consistency.
pub fn check_against_oracles(field: &ScalarField, tree: &ContourTree) {
    let mesh = field.mesh();
    let n = field.len();
    let rank = ranks(field);

    // The tree is a tree: V - 1 superarcs, connected, arcs point up, every
    // vertex placed once, arc vertices ascending and strictly inside.
    assert_eq!(
        tree.arcs().len() + 1,
        tree.nodes().len().max(1),
        "superarcs = supernodes - 1"
    );
    let edges = augmented_edges(tree);
    assert_eq!(edges.len(), n - 1, "augmented tree has n - 1 arcs");
    for &(lo, hi) in &edges {
        assert!(rank[lo] < rank[hi], "arc ({lo},{hi}) points down");
    }
    let tree_label = {
        let mut p: Vec<usize> = (0..n).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        for &(a, b) in &edges {
            let (ra, rb) = (find(&mut p, a), find(&mut p, b));
            p[ra] = rb;
        }
        (0..n).filter(|&v| find(&mut p, v) == v).count()
    };
    assert_eq!(tree_label, 1, "augmented tree is connected");
    for (a, _) in tree.arcs().iter().enumerate() {
        for v in tree.arc_vertices(ArcId(a as u32)) {
            assert_eq!(tree.place(v), VertexPlace::Arc(ArcId(a as u32)));
        }
    }
    for (i, node) in tree.nodes().iter().enumerate() {
        assert_eq!(
            tree.place(node.vertex),
            VertexPlace::Node(flexiso::tree::NodeId(i as u32))
        );
        assert_eq!(
            tree.up_arcs(flexiso::tree::NodeId(i as u32)).len(),
            usize::from(node.up)
        );
        assert_eq!(
            tree.down_arcs(flexiso::tree::NodeId(i as u32)).len(),
            usize::from(node.down)
        );
    }

    // (a) join and split trees.
    let jt_def = sweep_tree_by_definition(&mesh, &rank, true);
    let st_def = sweep_tree_by_definition(&mesh, &rank, false);
    assert_eq!(
        sweep_tree_of_graph(n, &edges, &rank, true),
        jt_def,
        "join tree"
    );
    assert_eq!(
        sweep_tree_of_graph(n, &edges, &rank, false),
        st_def,
        "split tree"
    );

    // (b) degrees by definition, for every vertex.
    let mut up_deg = vec![0u32; n];
    let mut down_deg = vec![0u32; n];
    for v in 0..n {
        for (up, deg) in [(true, &mut up_deg), (false, &mut down_deg)] {
            let beyond = |w: usize| {
                if up {
                    rank[w] > rank[v]
                } else {
                    rank[w] < rank[v]
                }
            };
            let label = flood_components(&mesh, beyond);
            let adjacent: BTreeSet<usize> = neighbours(&mesh, v)
                .into_iter()
                .filter(|&u| beyond(u))
                .map(|u| label[u])
                .collect();
            deg[v] = adjacent.len() as u32;
        }
    }
    for v in 0..n as u32 {
        let (up, down) = match tree.place(v) {
            VertexPlace::Node(id) => (tree.node(id).up.into(), tree.node(id).down.into()),
            VertexPlace::Arc(_) => (1, 1),
        };
        assert_eq!(
            (up, down),
            (up_deg[v as usize], down_deg[v as usize]),
            "degrees of vertex {v}"
        );
    }

    // (c) level set components at isovalues between consecutive values.
    let mut values: Vec<f64> = (0..n as u32).map(|v| field.value(v)).collect();
    values.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
    values.dedup();
    for w in values.windows(2) {
        let h = 0.5 * (w[0] + w[1]);
        let spanning = tree
            .arcs()
            .iter()
            .filter(|a| {
                field.value(tree.node(a.lower).vertex) < h
                    && field.value(tree.node(a.upper).vertex) > h
            })
            .count();
        assert_eq!(
            spanning,
            level_set_components(field, h),
            "components at h = {h}"
        );
    }
}
