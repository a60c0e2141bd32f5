//! The explorer's ids and what crosses from its jobs to the GPU: newtype
//! ids for selected contours, and contour meshes made ready for the
//! renderer on the thread that extracted them.

use std::sync::Arc;

use crate::contour::ContourMesh;
use crate::render::PreparedMesh;

/// A selected contour, by the order it was picked (never reused while the
/// explorer runs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ContourId(pub u64);

impl std::fmt::Display for ContourId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// `mesh` made ready for the GPU, for the threads that extract contours
/// (a contour mesh is always well formed; None would mean a bug, logged).
pub fn prepare(mesh: &ContourMesh) -> Option<Arc<PreparedMesh>> {
    prepare_reusing(mesh, PreparedMesh::default())
}

/// [`prepare`] into `spare`'s arrays ([`PreparedMesh::new_reusing`]).
pub fn prepare_reusing(mesh: &ContourMesh, spare: PreparedMesh) -> Option<Arc<PreparedMesh>> {
    let (p, n, i) = (&mesh.positions, &mesh.normals, &mesh.indices);
    match PreparedMesh::new_known(p, n, i, mesh.into(), spare) {
        Ok(m) => Some(Arc::new(m)),
        Err(e) => {
            eprintln!(
                "flexiso: contour of arc {:?} cannot be drawn: {e}",
                mesh.arc
            );
            None
        }
    }
}
