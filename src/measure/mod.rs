//! Measures of the contour tree's superarcs: local geometric measures for
//! simplification ([`geometric`]) and the topology of contours ([`betti`]).

pub mod betti;
pub mod geometric;
