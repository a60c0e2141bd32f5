//! Every shared volume gives exactly the current engine's tree with the
//! Raichel-Seshadhri engine (skipped without the data folder).

mod common;

use flexiso::field::io::{ReadOptions, read_volume};
use flexiso::progress::Progress;
use flexiso::tree::raichel_seshadhri;
use flexiso::tree::{ArcId, ContourTree};

fn check_dataset(name: &str) {
    let Some(path) = common::dataset(name) else {
        return;
    };
    let field = read_volume(&path, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .field;
    let (old, _) = ContourTree::from_field(&field, &Progress::new()).expect("not cancelled");
    let (new, _) =
        raichel_seshadhri::from_field(&field, false, &Progress::new()).expect("not cancelled");
    assert_eq!(new.nodes(), old.nodes(), "{name}: supernodes");
    assert_eq!(new.arcs(), old.arcs(), "{name}: superarcs");
    for a in 0..old.arcs().len() as u32 {
        assert_eq!(
            new.arc_vertices(ArcId(a)),
            old.arc_vertices(ArcId(a)),
            "{name}: regular vertices of arc {a}"
        );
    }
    for v in 0..field.len() as u32 {
        assert_eq!(new.place(v), old.place(v), "{name}: place of vertex {v}");
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
    nucleon: "nucleon.nrrd",
    marschner_lobb: "marschner_lobb.nrrd",
    silicium: "silicium.nrrd",
    fuel: "fuel.nrrd",
    neghip: "neghip.nrrd",
    hydrogen_atom: "hydrogen_atom.nrrd",
    tooth: "tooth.nrrd",
    engine: "engine.nrrd",
    boston_teapot: "boston_teapot.nrrd",
    aneurism: "aneurism.nrrd",
    bonsai: "bonsai.nrrd",
    brainweb_t1: "brainweb_t1.nrrd",
    colin27_ch2: "colin27_ch2.nrrd",
    colin27_ch2better: "colin27_ch2better.nrrd",
    inia19_t1_brain: "inia19_t1_brain.nrrd",
    mni152_t1: "mni152_t1.nrrd",
}
