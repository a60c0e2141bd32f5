//! The contour tree of every volume in the shared data folder: it is a tree,
//! the degrees of sampled vertices match the definition (components of the
//! superlevel / sublevel set adjacent to the vertex, found by flooding the
//! mesh), and building twice gives the same tree.

mod common;

use flexiso::field::ScalarField;
use flexiso::field::io::{ReadOptions, read_volume};
use flexiso::mesh::Mesh;
use flexiso::progress::Progress;
use flexiso::tree::{ArcId, ContourTree, VertexPlace};

/// Number of components of {w beyond v} (above v when `up`) that touch v,
/// by flooding the mesh from each neighbour beyond v. The floods advance in
/// lockstep, one vertex each per round, and merge when they meet; the count
/// is known once at most one group of merged floods can still grow. So a
/// saddle costs about the size of its smaller components, never a flood of
/// the whole volume.
fn degree_by_flooding(field: &ScalarField, v: u32, up: bool) -> u32 {
    let mesh = field.mesh();
    let beyond = |w: u32| {
        if up {
            field.is_above(w, v)
        } else {
            field.is_above(v, w)
        }
    };
    let mut starts = Vec::new();
    mesh.for_each_neighbour(v, |u| {
        if beyond(u) {
            starts.push(u)
        }
    });
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let k = starts.len();
    let mut group: Vec<usize> = (0..k).collect();
    let mut owner = std::collections::HashMap::new();
    let mut frontier: Vec<std::collections::VecDeque<u32>> = vec![Default::default(); k];
    for (i, &s) in starts.iter().enumerate() {
        match owner.get(&s) {
            Some(&j) => {
                let (a, b) = (find(&mut group, i), find(&mut group, j));
                group[a] = b;
            }
            None => {
                owner.insert(s, i);
                frontier[i].push_back(s);
            }
        }
    }
    loop {
        let mut growing = std::collections::HashSet::new();
        for (i, f) in frontier.iter().enumerate() {
            if !f.is_empty() {
                growing.insert(find(&mut group, i));
            }
        }
        if growing.len() <= 1 {
            break;
        }
        // Indices, not iterators: the closure below pushes into `frontier`.
        #[allow(clippy::needless_range_loop)]
        for i in 0..k {
            let Some(x) = frontier[i].pop_front() else {
                continue;
            };
            mesh.for_each_neighbour(x, |w| {
                if !beyond(w) {
                    return;
                }
                match owner.get(&w) {
                    Some(&j) => {
                        let (a, b) = (find(&mut group, i), find(&mut group, j));
                        group[a] = b;
                    }
                    None => {
                        owner.insert(w, i);
                        frontier[i].push_back(w);
                    }
                }
            });
        }
    }
    (0..k)
        .map(|i| find(&mut group, i))
        .collect::<std::collections::HashSet<_>>()
        .len() as u32
}

fn check_dataset(name: &str) {
    let Some(path) = common::dataset(name) else {
        return;
    };
    let field = read_volume(&path, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .field;
    let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");

    // A tree: V - 1 superarcs; connected (union-find over the superarcs);
    // every vertex placed, each arc's vertices strictly between its ends.
    let nodes = tree.nodes().len();
    assert_eq!(
        tree.arcs().len() + 1,
        nodes,
        "{name}: superarcs = supernodes - 1"
    );
    let mut comp: Vec<usize> = (0..nodes).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for arc in tree.arcs() {
        let (a, b) = (
            find(&mut comp, arc.upper.0 as usize),
            find(&mut comp, arc.lower.0 as usize),
        );
        assert_ne!(a, b, "{name}: a cycle through superarc {arc:?}");
        comp[a] = b;
    }
    let mut placed = tree.nodes().len();
    for (a, arc) in tree.arcs().iter().enumerate() {
        let (hi, lo) = (tree.node(arc.upper).vertex, tree.node(arc.lower).vertex);
        assert!(field.is_above(hi, lo), "{name}: arc upside down");
        let verts = tree.arc_vertices(ArcId(a as u32)).to_vec();
        placed += verts.len();
        for w in verts.windows(2) {
            assert!(
                field.is_above(w[1], w[0]),
                "{name}: arc vertices out of order"
            );
        }
        if let (Some(&first), Some(&last)) = (verts.first(), verts.last()) {
            assert!(
                field.is_above(first, lo) && field.is_above(hi, last),
                "{name}: vertex outside its arc"
            );
        }
    }
    assert_eq!(
        placed,
        field.len(),
        "{name}: every vertex on exactly one arc or node"
    );

    // Degrees by definition on a sample: every 997th node and a spread of
    // vertices through the volume.
    let n = field.len() as u32;
    let sample = tree
        .nodes()
        .iter()
        .step_by(997)
        .map(|node| node.vertex)
        .chain((1..=12).map(|k| (n as u64 * k / 13) as u32));
    for v in sample {
        let (up, down) = match tree.place(v) {
            VertexPlace::Node(id) => (tree.node(id).up.into(), tree.node(id).down.into()),
            VertexPlace::Arc(_) => (1, 1),
        };
        assert_eq!(
            (up, down),
            (
                degree_by_flooding(&field, v, true),
                degree_by_flooding(&field, v, false)
            ),
            "{name}: degrees of vertex {v}"
        );
    }

    // Deterministic.
    let (again, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
    assert_eq!(
        again.nodes(),
        tree.nodes(),
        "{name}: nodes differ between runs"
    );
    assert_eq!(
        again.arcs(),
        tree.arcs(),
        "{name}: arcs differ between runs"
    );

    // Divide and conquer: the same tree, vertex for vertex, in 3 blocks on
    // every thread and in 8 blocks on one.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    for (blocks, pool) in [(3, None), (8, Some(&one))] {
        let build = || ContourTree::from_field_in_blocks(&field, blocks, &Progress::new());
        let (blocked, _) = match pool {
            Some(p) => p.install(build),
            None => build(),
        }
        .expect("not cancelled");
        assert_eq!(
            blocked.nodes(),
            tree.nodes(),
            "{name}: nodes in {blocks} blocks"
        );
        assert_eq!(
            blocked.arcs(),
            tree.arcs(),
            "{name}: arcs in {blocks} blocks"
        );
        for a in 0..tree.arcs().len() as u32 {
            assert_eq!(
                blocked.arc_vertices(ArcId(a)),
                tree.arc_vertices(ArcId(a)),
                "{name}: vertices of arc {a} in {blocks} blocks"
            );
        }
    }
}

macro_rules! dataset_tests {
    ($($test:ident: $file:expr,)*) => {$(
        #[test]
        fn $test() {
            check_dataset($file);
        }
    )*};
}

dataset_tests! {
    nucleon_tree_is_valid: "nucleon.nrrd",
    marschner_lobb_tree_is_valid: "marschner_lobb.nrrd",
    silicium_tree_is_valid: "silicium.nrrd",
    fuel_tree_is_valid: "fuel.nrrd",
    neghip_tree_is_valid: "neghip.nrrd",
    hydrogen_atom_tree_is_valid: "hydrogen_atom.nrrd",
    tooth_tree_is_valid: "tooth.nrrd",
    engine_tree_is_valid: "engine.nrrd",
    boston_teapot_tree_is_valid: "boston_teapot.nrrd",
    aneurism_tree_is_valid: "aneurism.nrrd",
    bonsai_tree_is_valid: "bonsai.nrrd",
    brainweb_t1_tree_is_valid: "brainweb_t1.nrrd",
    colin27_ch2_tree_is_valid: "colin27_ch2.nrrd",
    colin27_ch2better_tree_is_valid: "colin27_ch2better.nrrd",
    mni152_t1_tree_is_valid: "mni152_t1.nrrd",
    inia19_t1_brain_tree_is_valid: "inia19_t1_brain.nrrd",
}

#[test]
fn every_dataset_in_the_folder_has_a_test() {
    let Some(dir) = common::data_dir() else {
        return;
    };
    let tested = include_str!("tree_datasets.rs");
    for entry in std::fs::read_dir(dir).expect("data folder lists") {
        let name = entry
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .into_owned();
        if name.ends_with(".nrrd") {
            assert!(
                tested.contains(&format!("\"{name}\"")),
                "{name} has no test"
            );
        }
    }
}
