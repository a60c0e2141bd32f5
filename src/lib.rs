//! flexiso: flexible isosurfaces through the contour tree.
//!
//! The pipeline, each step in its own module, data flowing one way:
//!
//! 1. [`field`]: a volume is read ([`field::io`]) or made ([`field::synthetic`])
//!    into a [`field::ScalarField`]; its vertices are sorted by value, ties by id.
//! 2. [`mesh`]: the grid is triangulated implicitly (Freudenthal, 14 neighbours).
//! 3. [`tree`]: join and split trees by union-find sweeps, merged into the
//!    augmented [`tree::ContourTree`].
//! 4. [`measure`]: local geometric measures (height, volume, hypervolume) and
//!    Betti numbers of the contours of each superarc.
//! 5. [`simplify`]: the pruning sequence by leaf pruning and vertex
//!    reduction, any level of simplification, the simplification curve.
//! 6. [`contour`]: path seeds and contour following: the single contour of one
//!    arc at one isovalue as a triangle mesh.
//! 7. [`render`] and [`app`]: the wgpu renderer and the egui explorer, which
//!    only call the modules above.

pub mod app;
pub mod cli;
pub mod contour;
pub mod field;
pub mod measure;
pub mod mesh;
pub mod output;
pub mod pages;
pub mod progress;
pub mod render;
pub mod session;
pub mod simplify;
pub mod tree;
