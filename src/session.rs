//! Sessions: a scene the user composed (which contours, at which
//! isovalues, in which colours and names, the measure, the level of
//! simplification, the camera), saved as JSON and opened again.
//!
//! ```json
//! {"format": "flexiso-session", "version": 1, "volume": "brain.nrrd",
//!  "dims": [181, 217, 181], "measure": "hypervolume", "arcs_shown": 100,
//!  "camera": {"target": [90, 108, 90], "distance": 400, "yaw": -1.05,
//!             "pitch": 0.44, "fov_y": 0.61},
//!  "contours": [{"superarc": [UPPER, LOWER], "isovalue": 80.5,
//!                "color": "#e6194b", "name": "brain", "visible": true}],
//!  "slices": {"x": 90, "z": 60},
//!  "clip": {"axis": "y", "at": 0.5, "keep": "above"},
//!  "cut_box": {"min": [0.5, 0.0, 0.5], "max": [1.0, 0.5, 1.0]},
//!  "view": {"labels": true, "legend": true, "triad": true, "slices_panel": true}}
//! ```
//!
//! `slices`, `clip`, `cut_box` and `view` are optional (version 1 files
//! without them open as before): `slices` holds the grid index of each
//! slice shown (an axis left out shows none), `clip` the clipping plane
//! across one axis at a fraction `at` of the volume's box, keeping what
//! lies `below` or `above` it, `cut_box` a box cut away from every
//! contour, its corners as fractions of the volume's box, and `view` the
//! 3D view's switches.
//!
//! A contour is named as in the selection (see `app::selection`): by the
//! original superarc it lies on, spelt as the vertex ids of its upper and
//! lower nodes (as `flexiso tree --json` writes `arcs`), and its isovalue.
//! That pair names one contour of the unsimplified tree, so it survives any
//! level of simplification and any measure. `volume` is absolute or
//! relative to the session file. Fields left out take their defaults
//! ([`Session::default`]); fields this version does not know are ignored.
//!
//! Placing a session on a volume ([`Session::place`]) checks every contour
//! against the volume's tree: a superarc that is not there, or an isovalue
//! outside its range, means the volume changed since the session was saved;
//! such contours are reported, the others are placed.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::field::ScalarField;
use crate::tree::{ArcId, ContourTree};

/// The value of the `format` field.
pub const FORMAT: &str = "flexiso-session";
/// The version this code writes and reads.
pub const VERSION: u32 = 1;

/// What can go wrong reading or writing a session.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The file cannot be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The session file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file is not valid session JSON.
    #[error("{path}: not a flexiso session: {message}")]
    Parse {
        /// The session file.
        path: PathBuf,
        /// What is wrong, with the line and column.
        message: String,
    },
    /// A session of another format or a newer version.
    #[error("{path}: {message}")]
    Unsupported {
        /// The session file.
        path: PathBuf,
        /// What is unsupported.
        message: String,
    },
}

/// The camera of the 3D view (see `render::Camera`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraState {
    /// The point looked at.
    pub target: [f32; 3],
    /// Distance from the target to the eye.
    pub distance: f32,
    /// Angle around world +Z, radians.
    pub yaw: f32,
    /// Elevation, radians.
    pub pitch: f32,
    /// Vertical field of view, radians.
    pub fov_y: f32,
}

/// One contour of a session.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SessionContour {
    /// Vertex ids of the upper and lower node of the original superarc.
    pub superarc: [u32; 2],
    /// The isovalue (the level set at `isovalue + ε`).
    pub isovalue: f64,
    /// `#rrggbb`; empty: the next colour of the palette.
    pub color: String,
    /// The user's name for it (may be empty).
    pub name: String,
    /// Drawn in the 3D view.
    pub visible: bool,
}

impl Default for SessionContour {
    fn default() -> Self {
        SessionContour {
            superarc: [0, 0],
            isovalue: 0.0,
            color: String::new(),
            name: String::new(),
            visible: true,
        }
    }
}

/// A saved scene (see the module doc for the format).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Session {
    /// Always [`FORMAT`].
    pub format: String,
    /// [`VERSION`] when written by this code.
    pub version: u32,
    /// The volume: a file (absolute, or relative to the session file) or
    /// a synthetic spec (`synthetic:64`).
    pub volume: String,
    /// The volume's grid size when saved (a check that it did not change).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dims: Option<[usize; 3]>,
    /// The measure ranking the leaves (`height`, `volume`, `hypervolume`).
    pub measure: String,
    /// Arcs of the simplified tree shown.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arcs_shown: Option<usize>,
    /// The 3D view's camera; none: fitted to the volume.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraState>,
    /// The contours, in the order they were picked.
    pub contours: Vec<SessionContour>,
    /// The slices shown (none: no slice).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slices: Option<SessionSlices>,
    /// The clipping plane (none: no cut).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clip: Option<SessionClip>,
    /// The cut-away box (none: no box).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cut_box: Option<SessionCutBox>,
    /// The 3D view's switches (none: their defaults).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view: Option<SessionView>,
}

/// An axis-aligned box cut away from every contour, its corners as
/// fractions of the volume's box along x, y and z (0..=1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SessionCutBox {
    /// The low corner.
    pub min: [f32; 3],
    /// The high corner.
    pub max: [f32; 3],
}

impl Default for SessionCutBox {
    fn default() -> Self {
        SessionCutBox {
            min: [0.5; 3],
            max: [1.0; 3],
        }
    }
}

impl SessionCutBox {
    /// The box in world coordinates for a volume box `lo..hi`: fractions
    /// clamped to 0..=1 (not a number: the default's), corners sorted.
    pub fn world(&self, lo: [f32; 3], hi: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        let d = SessionCutBox::default();
        let f = |v: f32, dv: f32| if v.is_finite() { v.clamp(0.0, 1.0) } else { dv };
        let mut a = [0.0; 3];
        let mut b = [0.0; 3];
        for i in 0..3 {
            let (p, q) = (f(self.min[i], d.min[i]), f(self.max[i], d.max[i]));
            let (p, q) = (p.min(q), p.max(q));
            a[i] = lo[i] + p * (hi[i] - lo[i]);
            b[i] = lo[i] + q * (hi[i] - lo[i]);
        }
        (a, b)
    }
}

/// The grid index of each slice shown; an axis left out shows none.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct SessionSlices {
    /// The slice normal to x.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub x: Option<usize>,
    /// The slice normal to y.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub y: Option<usize>,
    /// The slice normal to z.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub z: Option<usize>,
}

impl SessionSlices {
    /// Per axis (x, y, z).
    pub fn as_array(&self) -> [Option<usize>; 3] {
        [self.x, self.y, self.z]
    }

    /// From per-axis indices.
    pub fn from_array([x, y, z]: [Option<usize>; 3]) -> Self {
        SessionSlices { x, y, z }
    }
}

/// A clipping plane across one axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SessionClip {
    /// `x`, `y` or `z`.
    pub axis: String,
    /// Where, as a fraction of the volume's box along the axis (0..=1).
    pub at: f32,
    /// `below` or `above`: the side kept.
    pub keep: String,
}

impl Default for SessionClip {
    fn default() -> Self {
        SessionClip {
            axis: "y".into(),
            at: 0.5,
            keep: "above".into(),
        }
    }
}

impl SessionClip {
    /// The axis index (0, 1, 2), None for an unknown name.
    pub fn axis_index(&self) -> Option<usize> {
        ["x", "y", "z"].iter().position(|a| *a == self.axis)
    }

    /// Whether the side below `at` is kept (anything but `above`).
    pub fn keep_below(&self) -> bool {
        self.keep != "above"
    }
}

/// The 3D view's switches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct SessionView {
    /// Contour names drawn beside the contours.
    pub labels: bool,
    /// The legend of the visible contours.
    pub legend: bool,
    /// The axis triad.
    pub triad: bool,
    /// The slice panel is open.
    pub slices_panel: bool,
}

impl Default for SessionView {
    fn default() -> Self {
        SessionView {
            labels: false,
            legend: true,
            triad: true,
            slices_panel: false,
        }
    }
}

impl Default for Session {
    fn default() -> Self {
        Session {
            format: FORMAT.into(),
            version: VERSION,
            volume: String::new(),
            dims: None,
            measure: crate::simplify::Measure::default().name().into(),
            arcs_shown: None,
            camera: None,
            contours: Vec::new(),
            slices: None,
            clip: None,
            cut_box: None,
            view: None,
        }
    }
}

/// A session's contour placed on a volume's tree.
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedContour {
    /// The superarc it lies on.
    pub superarc: ArcId,
    /// Its isovalue.
    pub isovalue: f64,
    /// Its colour, when the session gave a valid one.
    pub colour: Option<[u8; 3]>,
    /// Its name.
    pub name: String,
    /// Drawn.
    pub visible: bool,
}

/// What [`Session::place`] found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Placement {
    /// The contours that lie on the volume's tree, in the session's order.
    pub contours: Vec<PlacedContour>,
    /// One line per problem (a contour left out, a bad colour, other dims).
    pub problems: Vec<String>,
}

impl Session {
    /// Parses session JSON (`path` names it in errors).
    pub fn from_json(text: &str, path: &Path) -> Result<Self, SessionError> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| SessionError::Parse {
                path: path.into(),
                message: e.to_string(),
            })?;
        let format = value.get("format").and_then(|f| f.as_str());
        if format != Some(FORMAT) {
            return Err(SessionError::Unsupported {
                path: path.into(),
                message: format!(
                    "\"format\" is {}, expected \"{FORMAT}\"",
                    format.map_or("missing".to_string(), |f| format!("\"{f}\""))
                ),
            });
        }
        let s: Session = serde_json::from_value(value).map_err(|e| SessionError::Parse {
            path: path.into(),
            message: e.to_string(),
        })?;
        if s.version > VERSION {
            return Err(SessionError::Unsupported {
                path: path.into(),
                message: format!(
                    "version {} is newer than this flexiso reads ({VERSION}): update flexiso",
                    s.version
                ),
            });
        }
        Ok(s)
    }

    /// Reads a session file.
    pub fn read(path: &Path) -> Result<Self, SessionError> {
        let text = std::fs::read_to_string(path).map_err(|source| SessionError::Io {
            path: path.into(),
            source,
        })?;
        Self::from_json(&text, path)
    }

    /// The session as pretty JSON.
    pub fn to_json(&self) -> String {
        // Plain data of strings and numbers: serialising cannot fail.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Writes the session to `path`, whole or not at all
    /// ([`crate::output::write_whole`]): a crash never leaves half a session.
    pub fn write(&self, path: &Path) -> Result<(), SessionError> {
        let io = |source| SessionError::Io {
            path: path.into(),
            source,
        };
        let json = self.to_json() + "\n";
        crate::output::write_whole(path, |out| std::io::Write::write_all(out, json.as_bytes()))
            .map_err(io)
    }

    /// The volume to open for a session read from `session_path`: a
    /// relative path is taken from the session file's folder; a synthetic
    /// spec stays as it is.
    pub fn volume_input(&self, session_path: &Path) -> String {
        let v = Path::new(&self.volume);
        let synthetic = matches!(
            crate::field::source::synthetic_spec(&self.volume),
            Ok(Some(_))
        );
        if v.is_absolute() || synthetic {
            return self.volume.clone();
        }
        let dir = session_path.parent().unwrap_or(Path::new(""));
        dir.join(v).to_string_lossy().into_owned()
    }

    /// How a session saved at `session_path` spells `volume`: relative
    /// when the volume lies in the session's folder or below, else
    /// absolute.
    pub fn spell_volume(volume: &Path, session_path: &Path) -> String {
        let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        let vol = abs(volume);
        let dir = abs(session_path.parent().unwrap_or(Path::new("")));
        match vol.strip_prefix(&dir) {
            Ok(rel) if !rel.as_os_str().is_empty() => rel.to_string_lossy().into_owned(),
            _ => vol.to_string_lossy().into_owned(),
        }
    }

    /// The measure named, if it is one.
    pub fn measure(&self) -> Option<crate::simplify::Measure> {
        self.measure.parse().ok()
    }

    /// Places the session's contours on `tree` (of `field`): each one's
    /// superarc is looked up by its nodes' vertex ids and its isovalue
    /// checked against the superarc's range. See the module doc.
    pub fn place(&self, tree: &ContourTree, field: &ScalarField) -> Placement {
        let mut out = Placement::default();
        if let Some(d) = self.dims
            && d != field.dims()
        {
            let [x, y, z] = field.dims();
            out.problems.push(format!(
                "the volume changed: it is {x}×{y}×{z}, the session was saved on {}×{}×{}",
                d[0], d[1], d[2]
            ));
        }
        if !self.measure.is_empty() && self.measure().is_none() {
            out.problems.push(format!(
                "'{}' is not a measure (height, volume, hypervolume)",
                self.measure
            ));
        }
        let by_ends: HashMap<(u32, u32), ArcId> = tree
            .arcs()
            .iter()
            .enumerate()
            .map(|(i, a)| {
                (
                    (tree.node(a.upper).vertex, tree.node(a.lower).vertex),
                    ArcId(i as u32),
                )
            })
            .collect();
        for (i, c) in self.contours.iter().enumerate() {
            let label = if c.name.is_empty() {
                format!("contour {}", i + 1)
            } else {
                format!("contour {} ({})", i + 1, c.name)
            };
            let [u, l] = c.superarc;
            let Some(&arc) = by_ends.get(&(u, l)) else {
                out.problems.push(format!(
                    "{label}: superarc {u}:{l} is not in this volume's tree (the volume changed?)"
                ));
                continue;
            };
            let a = tree.arc(arc);
            let (hi, lo) = (
                field.value(tree.node(a.upper).vertex),
                field.value(tree.node(a.lower).vertex),
            );
            // The contours of a superarc exist at h + ε for h in [lo, hi).
            if !(c.isovalue >= lo && c.isovalue < hi) {
                out.problems.push(format!(
                    "{label}: isovalue {} is outside superarc {u}:{l}'s values {lo} .. {hi} (the volume changed?)",
                    c.isovalue
                ));
                continue;
            }
            let colour = if c.color.is_empty() {
                None
            } else {
                let parsed = parse_colour(&c.color);
                if parsed.is_none() {
                    out.problems.push(format!(
                        "{label}: colour '{}' is not #rrggbb; a palette colour instead",
                        c.color
                    ));
                }
                parsed
            };
            out.contours.push(PlacedContour {
                superarc: arc,
                isovalue: c.isovalue,
                colour,
                name: c.name.clone(),
                visible: c.visible,
            });
        }
        out
    }
}

/// `#rrggbb` (or `rrggbb`) as RGB.
pub fn parse_colour(s: &str) -> Option<[u8; 3]> {
    let h = s.trim().strip_prefix('#').unwrap_or(s.trim());
    if h.len() != 6 || !h.is_ascii() {
        return None;
    }
    let byte = |i: usize| u8::from_str_radix(&h[i..i + 2], 16).ok();
    Some([byte(0)?, byte(2)?, byte(4)?])
}

/// RGB as `#rrggbb`.
pub fn format_colour([r, g, b]: [u8; 3]) -> String {
    format!("#{r:02x}{g:02x}{b:02x}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::synthetic::Synthetic;
    use crate::progress::Progress;

    #[test]
    fn colours_round_trip_and_bad_ones_are_refused() {
        assert_eq!(parse_colour("#e6194b"), Some([0xe6, 0x19, 0x4b]));
        assert_eq!(format_colour([0xe6, 0x19, 0x4b]), "#e6194b");
        for bad in ["", "#12345", "#gggggg", "#1234567", "#ééé"] {
            assert_eq!(parse_colour(bad), None, "{bad}");
        }
    }

    #[test]
    fn fields_left_out_take_their_defaults() {
        let s = Session::from_json(
            r#"{"format": "flexiso-session", "version": 1, "volume": "v.nrrd",
                "contours": [{"superarc": [5, 3], "isovalue": 0.5}]}"#,
            Path::new("s.json"),
        )
        .expect("a session");
        assert_eq!(s.measure, "hypervolume");
        assert_eq!(s.camera, None);
        assert!(s.contours[0].visible);
        assert_eq!(s.contours[0].name, "");
        assert_eq!((s.slices, s.clip, s.view), (None, None, None));
        assert_eq!(s.cut_box, None);
    }

    #[test]
    fn slices_clip_and_view_round_trip_and_partial_ones_take_defaults() {
        let s = Session {
            volume: "v.nrrd".into(),
            slices: Some(SessionSlices::from_array([Some(3), None, Some(7)])),
            clip: Some(SessionClip {
                axis: "x".into(),
                at: 0.25,
                keep: "below".into(),
            }),
            cut_box: Some(SessionCutBox {
                min: [0.0, 0.25, 0.5],
                max: [0.5, 1.0, 1.0],
            }),
            view: Some(SessionView {
                labels: true,
                ..SessionView::default()
            }),
            ..Session::default()
        };
        let json = s.to_json();
        assert!(
            !json.contains("\"y\": null"),
            "absent slices are left out: {json}"
        );
        let back = Session::from_json(&json, Path::new("s.json")).expect("a session");
        assert_eq!(back, s);
        let partial = Session::from_json(
            r#"{"format": "flexiso-session", "version": 1, "volume": "v.nrrd",
                "clip": {"axis": "z"}, "view": {"labels": true}}"#,
            Path::new("s.json"),
        )
        .expect("a session");
        let clip = partial.clip.expect("a clip");
        assert_eq!(
            (clip.axis_index(), clip.at, clip.keep_below()),
            (Some(2), 0.5, false)
        );
        let view = partial.view.expect("view switches");
        assert!(view.labels && view.legend && view.triad && !view.slices_panel);
    }

    #[test]
    fn other_formats_and_newer_versions_are_refused_with_a_reason() {
        let p = Path::new("s.json");
        let e = Session::from_json(r#"{"arcs": []}"#, p).expect_err("not a session");
        assert!(e.to_string().contains("format"), "{e}");
        let e = Session::from_json(r#"{"format": "flexiso-session", "version": 9}"#, p)
            .expect_err("too new");
        assert!(e.to_string().contains("newer"), "{e}");
        let e = Session::from_json("{", p).expect_err("bad JSON");
        assert!(matches!(e, SessionError::Parse { .. }), "{e}");
    }

    #[test]
    fn relative_volumes_are_taken_from_the_session_folder() {
        let s = Session {
            volume: "data/v.nrrd".into(),
            ..Session::default()
        };
        assert_eq!(
            Path::new(&s.volume_input(Path::new("/x/y/s.json"))),
            Path::new("/x/y/data/v.nrrd")
        );
        let spelt = Session::spell_volume(Path::new("/x/y/data/v.nrrd"), Path::new("/x/y/s.json"));
        assert_eq!(Path::new(&spelt), Path::new("data/v.nrrd"));
        let spelt = Session::spell_volume(Path::new("/z/v.nrrd"), Path::new("/x/y/s.json"));
        assert_eq!(Path::new(&spelt), Path::new("/z/v.nrrd"));
        let synth = Session {
            volume: "synthetic:24".into(),
            ..Session::default()
        };
        assert_eq!(synth.volume_input(Path::new("/x/s.json")), "synthetic:24");
    }

    #[test]
    fn placing_keeps_the_contours_on_the_tree_and_reports_the_others() {
        let field = Synthetic::cube(16).generate();
        let (tree, _) = ContourTree::from_field(&field, &Progress::new()).expect("a tree");
        let a = tree.arc(ArcId(0));
        let (u, l) = (tree.node(a.upper).vertex, tree.node(a.lower).vertex);
        let (hi, lo) = (field.value(u), field.value(l));
        let good = SessionContour {
            superarc: [u, l],
            isovalue: 0.5 * (lo + hi),
            color: "#102030".into(),
            name: "brain".into(),
            visible: false,
        };
        let s = Session {
            dims: Some(field.dims()),
            contours: vec![
                good.clone(),
                SessionContour {
                    superarc: [u32::MAX, 0],
                    ..good.clone()
                },
                SessionContour {
                    isovalue: hi + 1.0,
                    ..good.clone()
                },
            ],
            ..Session::default()
        };
        let p = s.place(&tree, &field);
        assert_eq!(
            p.contours,
            vec![PlacedContour {
                superarc: ArcId(0),
                isovalue: good.isovalue,
                colour: Some([0x10, 0x20, 0x30]),
                name: "brain".into(),
                visible: false,
            }]
        );
        assert_eq!(p.problems.len(), 2, "{:?}", p.problems);
        assert!(
            p.problems[0].contains("contour 2 (brain)"),
            "{:?}",
            p.problems
        );
        let other = Session {
            dims: Some([1, 2, 3]),
            ..s
        };
        assert!(other.place(&tree, &field).problems[0].contains("volume changed"));
    }
}
