//! The explorer's panels, one struct (or function) per panel, each with
//! its own state and one `ui` call; they talk only through what the app
//! hands them (the dataset, the level, the [`crate::app::selection`]).

pub mod colour;
pub mod contour_list;
pub mod curve;
pub mod menu;
pub mod slices;
pub mod tree;
pub mod view3d;
